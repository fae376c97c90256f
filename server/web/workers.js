// The workers page: health and throughput of each worker, read every two seconds.
'use strict';

(() => {
  const body = document.querySelector('#workers tbody');
  const before = new Map();  // worker id -> [units done, time] at the last read

  async function load() {
    try {
      const reply = await farm.api('/api/v1/workers');
      const now = Date.now() / 1000;
      body.replaceChildren();
      for (const w of reply.workers) {
        const tr = document.createElement('tr');
        tr.id = 'worker-' + w.address;
        const done = Number(w.units_done);
        const last = before.get(w.worker_id);
        const rate = last && now > last[1] ? ((done - last[0]) / (now - last[1])).toFixed(1) : '-';
        before.set(w.worker_id, [done, now]);
        const state = w.state.replace('WORKER_STATE_', '').toLowerCase();
        const beat = w.last_heartbeat ? ((Date.now() - Date.parse(w.last_heartbeat)) / 1000).toFixed(1) + 's ago' : '-';
        farm.cell(tr, 'address', w.address);
        const why = w.quarantine_reason || w.back_off_reason || w.lost_reason || '';
        const kept_off = (w.blocked_jobs || []).length ? ' (kept off ' + w.blocked_jobs.length + ' job(s))' : '';
        farm.cell(tr, 'state ' + state.replace('_', '-'), state.replace('_', ' ') + (why ? ': ' + why : '') + kept_off);
        farm.cell(tr, '', w.threads ? String(w.threads) : '-');
        farm.cell(tr, '', (w.engines || []).join(', ') || '-');
        farm.cell(tr, 'done', String(done));
        farm.cell(tr, '', String(w.units_failed));
        farm.cell(tr, 'rate', rate);
        farm.cell(tr, '', beat);
        farm.cell(tr, 'current', (w.current || []).join('; ') || '-');
        body.append(tr);
      }
      document.getElementById('error').textContent = '';
    } catch (e) {
      document.getElementById('error').textContent = e.message;
    }
  }

  farm.header('/workers.html');
  load();
  setInterval(load, 2000);
})();
