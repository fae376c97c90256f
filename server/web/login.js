// The login page: a token for a session cookie, then back where the user was going.
'use strict';

document.getElementById('login').addEventListener('submit', async (e) => {
  e.preventDefault();
  try {
    await farm.post('/api/v1/login', { token: document.getElementById('token').value });
    // Back to a page of this dashboard only: '//elsewhere' or '/\elsewhere' would leave it.
    const next = new URL(new URLSearchParams(location.search).get('next') || '/', location.origin);
    location.href = next.origin === location.origin ? next.pathname + next.search : '/';
  } catch (err) {
    document.getElementById('error').textContent = err.message;
  }
});
