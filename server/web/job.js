// The job page: the frame refining live as units land (the units done so far, each sample pass,
// each merged frame), frame thumbnails of an animation, facts and statistics, the actions, the
// download links and the event log, kept live by the job's event stream.
'use strict';

(() => {
  const id = new URLSearchParams(location.search).get('id') || '';
  const error = document.getElementById('error');
  const live = document.getElementById('live');
  let job = null;
  let frame = null;        // the frame shown; null: follow the frame being rendered
  let lastLogged = 0;      // the log's newest entry shown
  let imageVersion = 0;
  let imageTimer = null;

  const show = (e) => { error.textContent = e.message; };
  const frames = () => {
    const out = [];
    const step = Math.max(1, job.frame_step);
    for (let f = job.frame_first; f <= job.frame_last && out.length < 10000; f += step) out.push(f);
    return out;
  };

  // The big image: fetched again at most every 300 ms, however fast units land.
  function refreshImage(f) {
    if (frame === null) frame = f;
    if (f !== undefined && f !== frame) return;
    if (imageTimer) return;
    imageTimer = setTimeout(() => {
      imageTimer = null;
      live.src = `/api/v1/jobs/${id}/live?frame=${frame}&v=${++imageVersion}`;
      document.getElementById('frame-label').textContent = farm.isAnimation(job) ? `frame ${frame}` : '';
    }, imageVersion === 0 ? 0 : 300);
  }

  function facts() {
    const dl = document.getElementById('facts');
    dl.replaceChildren();
    const add = (name, value, className) => {
      dl.append(farm.text(document.createElement('dt'), name));
      const dd = document.createElement('dd');
      if (value instanceof Node) dd.append(value); else dd.textContent = value;
      if (className) dd.className = className;
      dl.append(dd);
    };
    // Other jobs, each a link to its page, with a note ("any end") where one says how it is waited for.
    const jobLinks = (entries) => {
      const span = document.createElement('span');
      entries.forEach(([other, note], i) => {
        if (i) span.append(', ');
        const a = farm.text(document.createElement('a'), other);
        a.href = '/job.html?id=' + encodeURIComponent(other);
        a.className = 'id';
        span.append(a);
        if (note) span.append(` (${note})`);
      });
      return span;
    };
    const cap = (n) => (Number(n) ? String(n) : 'none');
    add('State', farm.stateOf(job), 'state ' + farm.stateOf(job));
    add('Progress', farm.progressText(job), 'progress');
    add('Priority', String(job.priority), 'priority');
    const waits = [...(job.after || []).map((j) => [j, '']), ...(job.after_any || []).map((j) => [j, 'any end'])];
    if (job.after_frames) waits.push([job.after_frames, 'frame by frame']);
    if (waits.length) add('Waits for', jobLinks(waits), 'after');
    if ((job.dependents || []).length) add('Waited for by', jobLinks(job.dependents.map((j) => [j, ''])), 'dependents');
    add('Max workers', cap(job.max_workers), 'max-workers');
    add('Max units in flight', cap(job.max_units_in_flight), 'max-units-in-flight');
    add('Owner', job.owner || '-');
    add('Engine', `${job.engine}, ${job.width}x${job.height}` + (job.passes > 1 ? `, ${job.passes} passes` : ''));
    if (farm.isAnimation(job)) add('Frames', `${job.frame_first} to ${job.frame_last} by ${job.frame_step}`);
    add('Submitted', farm.when(job.submitted_at));
    add('Started', farm.when(job.started_at));
    add('Finished', farm.when(job.finished_at));
    add('Duration', farm.duration(job));
    add('ETA', farm.eta(job), 'eta');
    if (job.tile_failures) add('Unit retries', String(job.tile_failures));
    if (job.failure_reason) add('Failure', job.failure_reason, 'failure');
    const s = job.stats || {};
    if (Number(s.samples)) add('Samples', String(s.samples));
    if (Number(s.rays)) add('Rays', String(s.rays));
    if (s.cpu_ms) add('CPU time', (s.cpu_ms / 1000).toFixed(2) + ' s');
    if (job.validation) add('Embree check', job.validation);
    const actions = document.getElementById('actions');
    actions.replaceChildren(farm.actionButtons(job, (reply) => {
      if (!reply) return;
      if (reply.bytes_freed !== undefined) { location.href = '/'; return; }
      update(reply.job || reply);
    }, show, true));
  }

  function thumbs() {
    const strip = document.getElementById('thumbs');
    if (!farm.isAnimation(job)) { strip.replaceChildren(); return; }
    const have = new Set([...strip.children].map((img) => Number(img.dataset.frame)));
    for (const f of frames()) {
      if (have.has(f)) continue;
      const img = document.createElement('img');
      img.dataset.frame = String(f);
      img.alt = `frame ${f}`;
      img.title = `frame ${f}`;
      img.addEventListener('error', () => { delete img.dataset.asked; });
      img.addEventListener('click', () => {
        frame = f;
        for (const t of strip.children) t.classList.toggle('chosen', t === img);
        refreshImage(f);
      });
      strip.append(img);
    }
  }

  // A thumbnail is asked for once its frame is merged (a frame_finished event, live or in the log),
  // and asked for again only if that failed.
  function thumbDone(f) {
    const img = document.querySelector(`#thumbs img[data-frame="${f}"]`);
    if (!img || img.dataset.asked) return;
    img.dataset.asked = '1';
    img.src = `/api/v1/jobs/${id}/file?kind=preview&frame=${f}`;
  }

  // The frames known to be merged: only theirs are linked for download (issue #32: links to frames
  // not merged yet led to errors).
  const mergedFrames = new Set();
  function frameMerged(f) {
    thumbDone(f);
    if (mergedFrames.has(f)) return;
    mergedFrames.add(f);
    downloads();
  }

  // Every frame of a job that succeeded is merged (its log may have dropped some merges past its
  // limit).
  function thumbsIfSucceeded() {
    if (job.state === 'JOB_STATE_SUCCEEDED' && farm.isAnimation(job)) for (const f of frames()) thumbDone(f);
  }

  function downloads() {
    const box = document.getElementById('downloads');
    box.replaceChildren();
    const link = (href, label) => {
      const a = document.createElement('a');
      a.href = href;
      a.textContent = label;
      box.append(a, ' ');
    };
    const succeeded = job.state === 'JOB_STATE_SUCCEEDED';
    const list = farm.isAnimation(job) ? frames().filter((f) => succeeded || mergedFrames.has(f))
                                       : (job.frames_done > 0 ? [job.frame_first] : []);
    if (list.length === 0) { box.textContent = 'nothing merged yet'; return; }
    for (const f of list.slice(0, 200)) {
      if (farm.isAnimation(job)) box.append(`frame ${f}: `);
      link(`/api/v1/jobs/${id}/file?kind=exr&frame=${f}`, 'EXR');
      link(`/api/v1/jobs/${id}/file?kind=preview&frame=${f}`, 'PNG');
      box.append(document.createElement('br'));
    }
    if (job.state === 'JOB_STATE_SUCCEEDED') link(`/api/v1/jobs/${id}/file?kind=video`, 'video (if the job made one)');
  }

  // Only GetJob fills a job's dependencies; the events' jobs and most actions' replies leave them
  // empty, so those keep the ones last read (an `updated` event, which adding some sends, reads
  // the job again).
  const LINKS = ['after', 'after_any', 'after_frames', 'dependents'];
  // A reread's reply may be older than events that came while it was on its way (the animation's
  // last merge and its success among them): then only its links are taken, since every change of
  // the job's state comes as an event of its own, in order, after the one shown.
  let eventsSeen = 0;
  const reread = () => {
    const asked = eventsSeen;
    return farm.api(`/api/v1/jobs/${id}`).then((j) => {
      if (eventsSeen === asked) { update(j, true); return; }
      for (const k of LINKS) job[k] = j[k];
      facts();
    });
  };

  function update(now, full = false) {
    const merged = job ? job.frames_done : 0;
    if (!full && job) for (const k of LINKS) now[k] = job[k];
    job = now;
    document.getElementById('title').textContent = `${job.name} (${job.job_id})`;
    document.title = `farm: ${job.name}`;
    facts();
    if (job.frames_done !== merged || job.state === 'JOB_STATE_SUCCEEDED') downloads();
    thumbsIfSucceeded();
  }

  function logEntry(number, at, event) {
    if (number <= lastLogged) return;
    lastLogged = number;
    if (event.frame_finished) frameMerged(event.frame_finished.frame);
    const tr = document.createElement('tr');
    farm.cell(tr, '', String(number));
    farm.cell(tr, '', new Date(at).toLocaleTimeString());
    farm.cell(tr, '', farm.describe(event));
    document.querySelector('#log tbody').append(tr);
  }

  async function loadLog() {
    let more = true;
    while (more) {
      const page = await farm.api(`/api/v1/jobs/${id}/log?after=${lastLogged}`);
      for (const e of page.entries) logEntry(e.number, e.at, e.event);
      more = page.more && page.entries.length > 0;
    }
  }

  async function start() {
    farm.header('');
    try {
      update(await farm.api(`/api/v1/jobs/${id}`), true);
      performance.mark('farm-job-shown');
      thumbs();
      downloads();
      refreshImage(job.frame_first);
      thumbsIfSucceeded();
      await loadLog();  // its merges ask for their frames' thumbnails
    } catch (e) { show(e); return; }
    farm.events(id, (event) => {
      ++eventsSeen;
      update(event.job);
      if (event.tile_finished) refreshImage(event.tile_finished.frame);
      if (event.pass_finished) refreshImage(event.pass_finished.frame);
      if (event.frame_finished) { refreshImage(event.frame_finished.frame); frameMerged(event.frame_finished.frame); }
      if (!event.tile_finished) loadLog().catch(show);  // the log numbers its entries: read them from it
      if (event.updated) reread().catch(show);
    }, () => reread().then(loadLog).catch(show));
  }
  live.addEventListener('error', () => { /* nothing rendered yet: the next event tries again */ });
  start();
})();
