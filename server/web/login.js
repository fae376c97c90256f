// The login page: a token for a session cookie, then back where the user was going.
'use strict';

document.getElementById('login').addEventListener('submit', async (e) => {
  e.preventDefault();
  try {
    await farm.post('/api/v1/login', { token: document.getElementById('token').value });
    const next = new URLSearchParams(location.search).get('next') || '/';
    location.href = next.startsWith('/') && !next.startsWith('//') ? next : '/';
  } catch (err) {
    document.getElementById('error').textContent = err.message;
  }
});
