// The jobs page: the newest jobs, filtered, kept live by the scheduler's event stream.
'use strict';

(() => {
  const body = document.querySelector('#jobs tbody');
  const error = document.getElementById('error');
  const shown = new Map();  // job id -> its row
  // A list read before an event arrived must not put back what the event replaced: rows that
  // events refreshed after the newest load was asked for stay as they are when its list lands.
  let loads = 0;
  const newer = new Set();
  let filter = { state: '', name: '' };

  function matches(job) {
    if (filter.state && farm.stateName(job.state) !== filter.state) return false;
    if (!filter.name) return true;
    const glob = new RegExp('^' + filter.name.replace(/[.+^${}()|[\]\\]/g, '\\$&').replace(/\*/g, '.*')
      .replace(/\?/g, '.') + '$', 'i');
    return glob.test(job.name);
  }

  function row(job) {
    const tr = document.createElement('tr');
    tr.id = 'job-' + job.job_id;
    const link = document.createElement('a');
    link.href = '/job.html?id=' + job.job_id;
    link.className = 'id';
    link.textContent = job.job_id;
    farm.cell(tr, '', link);
    farm.cell(tr, 'name', job.name);
    farm.cell(tr, 'owner', job.owner || '-');
    farm.cell(tr, 'state ' + farm.stateOf(job), farm.stateOf(job));
    const bar = document.createElement('progress');
    bar.max = Math.max(1, job.tiles_total);
    bar.value = job.tiles_done;
    const progress = farm.cell(tr, 'progress', bar);
    progress.append(' ', farm.text(document.createElement('span'), farm.progressText(job)));
    farm.cell(tr, 'priority', String(job.priority));
    farm.cell(tr, 'submitted', farm.when(job.submitted_at));
    farm.cell(tr, 'duration', farm.duration(job));
    farm.cell(tr, 'actions', farm.actionButtons(job, (reply) => {
      if (!reply) return;
      if (reply.bytes_freed !== undefined) {  // deleted: no event says so
        tr.remove();
        shown.delete(job.job_id);
        return;
      }
      refresh(reply.job || reply);
    }, show));
    farm.cell(tr, 'failure', job.failure_reason || '');
    return tr;
  }

  function show(e) { error.textContent = e.message; }

  // A job as it is now: its row replaced (or added on top when new and matching).
  function refresh(job) {
    if (!job || !job.job_id) { load(); return; }
    const old = shown.get(job.job_id);
    if (!matches(job)) {
      if (old) { old.remove(); shown.delete(job.job_id); }
      return;
    }
    const tr = row(job);
    if (old) old.replaceWith(tr); else body.prepend(tr);
    shown.set(job.job_id, tr);
    newer.add(job.job_id);
  }

  async function load() {
    const params = new URLSearchParams({ page_size: '200' });
    if (filter.state) params.set('state', filter.state);
    if (filter.name) params.set('name', filter.name);
    const mine = ++loads;
    newer.clear();
    try {
      const list = await farm.api('/api/v1/jobs?' + params);
      if (mine !== loads) return;  // a later load is on its way
      const kept = new Map([...newer].filter((id) => shown.has(id)).map((id) => [id, shown.get(id)]));
      body.replaceChildren();
      shown.clear();
      for (const job of list.jobs) {
        const tr = kept.get(job.job_id) || row(job);
        kept.delete(job.job_id);
        body.append(tr);
        shown.set(job.job_id, tr);
      }
      for (const [id, tr] of kept) {  // new since the list was read
        body.prepend(tr);
        shown.set(id, tr);
      }
      document.getElementById('count').textContent = `${list.jobs.length} job(s)` +
        (list.next_page_token ? ' (the newest 200)' : '');
      error.textContent = '';
    } catch (e) { show(e); }
  }

  document.getElementById('filters').addEventListener('submit', (e) => {
    e.preventDefault();
    filter = { state: document.getElementById('state').value, name: document.getElementById('name').value };
    load();
  });

  farm.header('/');
  load().then(() => {
    // A deleted job sends no event: its row goes when the page acts, or at the next load.
    farm.events('', (event) => refresh(event.job), load);
  });
  // Durations of running jobs move on without events.
  setInterval(() => { if (body.querySelector('.state.running')) load(); }, 30000);
})();
