// The dashboard's shared code: calls to the JSON API (/api/v1/, the RPCs' messages as JSON), the
// live event stream, and how jobs and events are shown. No framework, no build step.
'use strict';

const farm = (() => {
  // A call to the API; a scheduler that wants a login sends the browser to the login page.
  async function api(path, options = {}) {
    const init = { credentials: 'same-origin', ...options };
    if (init.body !== undefined) init.headers = { 'Content-Type': 'application/json' };
    const reply = await fetch(path, init);
    if (reply.status === 401 && !path.startsWith('/api/v1/login')) {
      location.href = '/login.html?next=' + encodeURIComponent(location.pathname + location.search);
      throw new Error('log in first');
    }
    const text = await reply.text();
    const body = text ? JSON.parse(text) : {};
    if (!reply.ok) throw new Error(body.message || reply.statusText);
    return body;
  }
  const post = (path, body = {}) => api(path, { method: 'POST', body: JSON.stringify(body) });

  const FINAL = ['JOB_STATE_SUCCEEDED', 'JOB_STATE_FAILED', 'JOB_STATE_CANCELLED'];
  const isFinal = (job) => FINAL.includes(job.state);
  // None of its units handed out yet: it may still be given jobs to wait for (AddDependencies).
  const notStarted = (job) => job.state === 'JOB_STATE_WAITING' ||
    (job.state === 'JOB_STATE_QUEUED' && (!job.started_at || job.started_at.startsWith('1970')));
  const stateName = (state) => String(state).replace('JOB_STATE_', '').toLowerCase();
  const stateOf = (job) => (job.paused && !isFinal(job) ? 'paused' : stateName(job.state));
  const units = () => 'units';  // one word for the scheduler's piece of work everywhere
  const isAnimation = (job) => job.frames_total > 1 || job.frame_first !== 0;
  function progressText(job) {
    const frames = isAnimation(job) ? `${job.frames_done}/${job.frames_total} frames, ` : '';
    return `${frames}${job.tiles_done}/${job.tiles_total} ${units(job)}`;
  }
  const seconds = (t) => (t ? Date.parse(t) / 1000 : 0);
  function when(t) {
    if (!t || t.startsWith('1970')) return '-';
    return new Date(t).toLocaleString();
  }
  // "42.0s", "3m05s", "2h10m", as server/common/job_eta.cpp's short_duration.
  function shortDuration(s) {
    s = Math.max(0, s);
    if (s < 60) return s.toFixed(1) + 's';
    if (s < 3600) return `${Math.floor(s / 60)}m${String(Math.floor(s % 60)).padStart(2, '0')}s`;
    return `${Math.floor(s / 3600)}h${String(Math.floor((s / 60) % 60)).padStart(2, '0')}m`;
  }
  function duration(job) {
    const start = seconds(job.started_at);
    if (!start) return '-';
    return shortDuration((seconds(job.finished_at) || Date.now() / 1000) - start);
  }
  // Time left at the units' measured rate, as server/common/job_eta.cpp's job_eta: '-' unless the
  // job runs, is not paused and has a unit done.
  function eta(job) {
    const start = seconds(job.started_at), done = Number(job.tiles_done || 0), total = Number(job.tiles_total || 0);
    if (job.state !== 'JOB_STATE_RUNNING' || job.paused || !start || done === 0 || done >= total) return '-';
    const elapsed = Date.now() / 1000 - start;
    return elapsed > 0 ? shortDuration(Math.ceil((elapsed / done) * (total - done))) : '-';
  }
  const unitRange = (first, count) => (count > 1 ? `units ${first}-${first + count - 1}` : `unit ${first}`);

  // One line for an event, as `farm log` prints it.
  function describe(event) {
    const job = event.job;
    if (event.state_changed) {
      const c = event.state_changed;
      if (c.from === 'JOB_STATE_UNSPECIFIED') return `submitted: ${stateName(c.to)}, ${job.tiles_total} units`;
      const why = c.to === 'JOB_STATE_FAILED' && job.failure_reason ? ': ' + job.failure_reason : '';
      const by = c.by ? ` by ${c.by}` : '';
      return `${stateName(c.from)} -> ${stateName(c.to)} (${progressText(job)})${by}${why}`;
    }
    if (event.tile_failed) {
      const f = event.tile_failed;
      return `${unitRange(f.tile_index, Math.max(1, f.tile_count))} failed on ${f.worker || 'the scheduler'}: ${f.reason}` +
        (f.will_retry ? ' (will retry)' : '');
    }
    if (event.tile_finished) {
      const f = event.tile_finished;
      return `${unitRange(f.tile_index, Math.max(1, f.tile_count))} of frame ${f.frame} done on ${f.worker}`;
    }
    if (event.frame_finished) return `frame ${event.frame_finished.frame} merged (${progressText(job)})`;
    if (event.pass_finished) {
      const p = event.pass_finished;
      return `frame ${p.frame}: sample pass ${p.pass + 1}/${p.passes} done`;
    }
    if (event.updated) return event.updated.change + (event.updated.by ? ` (by ${event.updated.by})` : '');
    return 'event';
  }

  // A cap typed in: a whole number from 0 (0: none).
  function capOf(text, what) {
    const n = Number(text.trim());
    if (text.trim() === '' || !Number.isInteger(n) || n < 0) throw new Error(`${what}: a whole number from 0, not '${text}'`);
    return n;
  }

  // The job actions, as buttons: each posts and hands the reply to `done`. `all`: also the caps
  // and the dependencies, which only the job page offers (the jobs table stays narrow).
  function actionButtons(job, done, fail, all = false) {
    const span = document.createElement('span');
    span.className = 'actions';
    const active = !isFinal(job);
    const add = (name, label, enabled, act) => {
      const b = document.createElement('button');
      b.className = name;
      b.textContent = label;
      b.disabled = !enabled;
      b.addEventListener('click', async () => {
        try {
          done(await act());
        } catch (e) {
          fail(e);
        }
      });
      span.append(b);
    };
    const base = `/api/v1/jobs/${job.job_id}/`;
    add('cancel', 'Cancel', active, () => post(base + 'cancel'));
    add('pause', job.paused ? 'Resume' : 'Pause', active, () => post(base + (job.paused ? 'resume' : 'pause')));
    add('retry', 'Retry', ['JOB_STATE_FAILED', 'JOB_STATE_CANCELLED'].includes(job.state), () => post(base + 'retry'));
    add('priority', 'Priority', true, () => {
      const p = prompt(`Priority of ${job.name} (higher runs first)`, String(job.priority));
      if (p === null) return Promise.resolve(null);
      return post(base + 'priority', { priority: parseInt(p, 10) });
    });
    add('delete', 'Delete', !active, () => (confirm(`Delete job ${job.name} and its files?`)
      ? post(base + 'delete') : Promise.resolve(null)));
    if (!all) return span;
    add('limits', 'Caps', active, () => {
      const w = prompt(`Most workers rendering ${job.name} at once (0: no cap)`, String(job.max_workers || 0));
      if (w === null) return Promise.resolve(null);
      const u = prompt(`Most units of ${job.name} out at once (0: no cap)`, String(job.max_units_in_flight || 0));
      if (u === null) return Promise.resolve(null);
      return post(base + 'limits', { maxWorkers: capOf(w, 'max workers'), maxUnitsInFlight: capOf(u, 'max units in flight') });
    });
    add('dependencies', 'Wait for', notStarted(job), () => {
      const ids = prompt(`Jobs ${job.name} is to wait for to succeed (whole ids, separated by spaces or commas)`, '');
      const after = (ids || '').split(/[\s,]+/).filter(Boolean);
      return after.length ? post(base + 'dependencies', { after }) : Promise.resolve(null);
    });
    return span;
  }

  // The scheduler's events (of one job, or of every job), in order; `resync` when some were lost.
  function events(job, onEvent, onResync) {
    const source = new EventSource('/api/v1/events' + (job ? '?job=' + encodeURIComponent(job) : ''));
    source.addEventListener('job', (e) => onEvent(JSON.parse(e.data), Number(e.lastEventId)));
    source.addEventListener('resync', () => onResync && onResync());
    // What happened before the stream opened (after the page read the farm), or while a broken
    // stream was being reconnected by the browser, came as no event: read again once it is open.
    source.addEventListener('open', () => onResync && onResync());
    return source;
  }

  async function header(here) {
    const nav = document.querySelector('header');
    nav.innerHTML = '<strong>farm</strong><a href="/">Jobs</a><a href="/workers.html">Workers</a>' +
      '<span class="who"></span>';
    for (const a of nav.querySelectorAll('a')) if (a.getAttribute('href') === here) a.className = 'here';
    try {
      const me = await api('/api/v1/whoami');
      nav.querySelector('.who').textContent = `${me.name} (${me.roles})`;
      if (me.tokens_required) {
        const out = document.createElement('button');
        out.textContent = 'Log out';
        out.addEventListener('click', async () => { await post('/api/v1/logout'); location.href = '/login.html'; });
        nav.append(out);
      }
    } catch (e) { /* the login page takes over */ }
  }

  const text = (element, value) => { element.textContent = value; return element; };
  function cell(row, className, value) {
    const td = document.createElement('td');
    if (className) td.className = className;
    if (value instanceof Node) td.append(value); else td.textContent = value;
    row.append(td);
    return td;
  }

  return { api, post, isFinal, stateOf, stateName, progressText, isAnimation, when, duration, eta, describe,
           actionButtons, events, header, text, cell };
})();
