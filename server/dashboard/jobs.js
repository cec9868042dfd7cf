// The jobs list and a job's page (summary, spread over seeds, failures, its episodes, two of
// which can be ticked to overlay them).
'use strict';

async function jobsPage() {
  const params = hashParams();
  const filters = params.getAll('label');
  const query = filters.map(l => 'label=' + encodeURIComponent(l)).join('&');
  const [jobs, workers] = await Promise.all([api('/api/jobs' + (query ? '?' + query : '')), api('/api/workers')]);
  const input = el('input', {type: 'text', name: 'label', placeholder: 'suite=nightly', value: filters.join(' ')});
  const form = el('form', {class: 'inline', onsubmit: ev => {
    ev.preventDefault();
    const q = input.value.trim().split(/\s+/).filter(Boolean).map(l => 'label=' + encodeURIComponent(l)).join('&');
    location.hash = '#/jobs' + (q ? '?' + q : '');
  }}, 'label filter', input, el('button', {type: 'submit'}, 'filter'));
  const rows = jobs.slice().reverse().map(j => el('tr', {class: 'job', 'data-id': j.id},
      el('td', {}, link('#/job/' + j.id, j.id)), el('td', {class: 'job-name'}, j.name),
      el('td', {}, labelsOf(j.labels)), el('td', {}, j.state),
      el('td', {}, progressBar(j), ` ${j.done}/${j.total}`, j.failed ? ` (${j.failed} failed)` : '',
         j.waiting ? el('div', {class: 'waiting'}, 'waiting: ' + j.waiting) : ''),
      el('td', {class: 'num'}, j.rate_per_s > 0 ? fmt(j.rate_per_s) + ' ep/s' : '–'),
      el('td', {class: 'num'}, j.state === 'running' ? duration(j.eta_s) : '–'),
      el('td', {}, new Date(j.created_ms).toISOString().replace('T', ' ').slice(0, 19)),
      el('td', {class: 'muted'}, provenanceText(j.provenance || {}))));
  const wrows = workers.map(w => el('tr', {},
      el('td', {}, w.worker_id), el('td', {}, w.host), el('td', {class: 'num'}, w.slots),
      el('td', {class: 'num'}, w.free_slots === undefined ? '–' : w.free_slots),
      el('td', {}, w.alive ? 'alive' : 'gone'),
      el('td', {class: 'num'}, w.last_seen_s === undefined ? '–' : fmt(w.last_seen_s, 1) + ' s ago'),
      el('td', {}, w.version || ''), el('td', {}, w.calibration_id || '')));
  show(el('h1', {}, 'Jobs'), form,
       table(['id', 'name', 'labels', 'state', 'progress', 'rate', 'ETA', 'created (UTC)', 'provenance'], rows),
       el('h2', {}, 'Workers'),
       wrows.length ? table(['worker', 'host', 'slots', 'free', 'state', 'last seen', 'version', 'calibration'], wrows)
                    : el('p', {class: 'muted'}, 'no workers'));
  if (jobs.some(j => j.state === 'running')) timer = setTimeout(route, 2000);
}

// The paper table's metrics lead; any other judged metric (info.metric_rules) follows.
const LEADING = ['success', 'flight_time_s', 'path_length_m', 'nav_cpu_util_pct', 'velocity_std_mps'];

// Metrics in display order: those with a direction first (info.metric_rules), then the rest.
function orderedMetrics(names) {
  const rules = info.metric_rules || {};
  const judged = n => names.has(n) && rules[n] && rules[n].direction !== 'none';
  const ruled = LEADING.filter(judged).concat(Object.keys(rules).filter(n => judged(n) && !LEADING.includes(n)));
  const rest = [...names].filter(n => !ruled.includes(n)).sort();
  return {ruled, rest};
}

async function jobPage(id) {
  const [job, summary, failures] = await Promise.all([
    api('/api/jobs/' + id), api('/api/jobs/' + id + '/summary?limit=1000'),
    api('/api/jobs/' + id + '/failures?limit=200')]);
  const cells = summary.cells;
  const names = new Set(cells.flatMap(c => Object.keys(c.metrics)));
  const {ruled, rest} = orderedMetrics(names);
  const rules = info.metric_rules || {};
  const statOf = (c, m) => (rules[m] && rules[m].success_only ? c.success_only[m] : c.metrics[m]);
  // The paper-style table: one row per cell, mean +- std of the judged metrics.
  const header = ['board', 'scenario', 'method', 'results', 'failed'].concat(ruled);
  const rows = cells.map(c => el('tr', {},
      el('td', {}, c.board), el('td', {}, c.scenario), el('td', {}, c.method),
      el('td', {class: 'num'}, c.results), el('td', {class: 'num'}, c.failed_episodes),
      ruled.map(m => {
        const st = statOf(c, m);
        return el('td', {class: 'num'}, st ? fmt(st.mean) + (st.n > 1 ? ' ± ' + fmt(st.std) : '') : '–');
      })));
  // Charts: per board x scenario, each method's spread over seeds (methods: whatever the job flew).
  const groups = [...new Set(cells.map(c => c.board + ' ' + c.scenario))];
  const methods = [...new Set(cells.map(c => c.method))];
  const cellOf = new Map(cells.map(c => [`${c.board} ${c.scenario}\n${c.method}`, c]));
  const charts = ruled.map(m => Plots.spread({
    title: m + (rules[m] && rules[m].success_only ? ' (successful flights)' : '') +
           (rules[m] ? ` — ${rules[m].direction} is better` : ''),
    groups, methods, range: rules[m] && rules[m].range,
    stats: (g, method) => { const c = cellOf.get(`${g}\n${method}`); return c ? statOf(c, m) || null : null; },
  }));
  const frows = failures.failures.map(f => el('tr', {},
      el('td', {}, f.state === 'failed' ? f.episode_id : link('#/episode/' + f.episode_id, f.episode_id)),
      el('td', {}, f.board), el('td', {}, f.scenario), el('td', {}, f.method), el('td', {class: 'num'}, f.seed),
      el('td', {}, f.state), el('td', {class: 'reason'}, f.reason)));
  const other = rest.map(m => el('tr', {}, el('td', {}, m),
      cells.map(c => el('td', {class: 'num'}, c.metrics[m] ? fmt(c.metrics[m].mean) : '–'))));
  const results = el('div', {id: 'results'});
  const overlayPick = pickTwo();
  show(el('h1', {}, 'Job ', el('span', {class: 'job-name'}, job.name), ' ', el('span', {class: 'muted'}, job.id)),
       el('p', {}, labelsOf(job.labels), ' ', job.state, ' ', progressBar(job), ` ${job.done}/${job.total} done`,
          job.failed ? `, ${job.failed} failed` : '', job.state === 'running' ? `, ETA ${duration(job.eta_s)}` : ''),
       el('p', {class: 'muted'}, provenanceText(job.provenance || {})),
       // Episodes no connected worker can run (a ROS method's without a worker offering ros).
       job.waiting ? el('p', {id: 'waiting', class: 'note'}, 'waiting: ' + job.waiting) : '',
       el('h2', {}, 'Summary'), table(header, rows),
       el('h2', {}, 'Spread over seeds'),
       el('p', {class: 'muted'}, 'per board x scenario and method: whisker min–max, box mean ± std, dot the mean; ' +
                                 'hover a group for its numbers, click a legend entry to hide a method'),
       el('div', {class: 'charts'}, charts),
       el('h2', {}, 'Failures and unsuccessful flights'),
       frows.length ? table(['episode', 'board', 'scenario', 'method', 'seed', 'state', 'reason'], frows)
                    : el('p', {class: 'muted'}, 'none'),
       el('h2', {}, 'Episodes'), overlayPick.note, results,
       el('h2', {}, 'Other metrics (mean)'),
       table(['metric'].concat(cells.map(c => `${c.board} ${c.scenario} ${c.method}`)), other));
  await resultsPager(id, results, 0, overlayPick);
  if (job.state === 'running') timer = setTimeout(route, 3000);
}

// Two flights ticked in the episode list (on any of its pages, or the same flight's other
// method) open on one set of charts: the overlay page.
function pickTwo() {
  const chosen = [];
  const note = el('p', {id: 'overlay-pick', class: 'muted'});
  const update = () => {
    if (chosen.length < 2) {
      note.replaceChildren(`tick two episodes to overlay their flights (${chosen.length} ticked)`);
    } else {
      note.replaceChildren(link(`#/overlay?a=${encodeURIComponent(chosen[0])}&b=${encodeURIComponent(chosen[1])}`,
                                `overlay ${chosen[0]} and ${chosen[1]}`));
    }
  };
  const box = id => {
    const input = el('input', {type: 'checkbox', class: 'pick', 'data-episode': id, title: 'overlay this flight'});
    input.checked = chosen.includes(id);
    input.onchange = () => {
      const at = chosen.indexOf(id);
      if (at >= 0) chosen.splice(at, 1);
      if (input.checked) chosen.push(id);
      // A third tick replaces the oldest.
      while (chosen.length > 2) {
        const dropped = chosen.shift();
        document.querySelectorAll(`input.pick[data-episode="${dropped}"]`).forEach(n => { n.checked = false; });
      }
      update();
    };
    return input;
  };
  update();
  return {note, box};
}

async function resultsPager(id, box, offset, pick) {
  const limit = 50;
  const page = await api(`/api/jobs/${id}/results?offset=${offset}&limit=${limit}`);
  const rows = page.results.map(r => el('tr', {},
      el('td', {}, pick.box(r.episode_id)),
      el('td', {}, link('#/episode/' + r.episode_id, r.episode_id)), el('td', {}, r.board), el('td', {}, r.scenario),
      el('td', {}, r.method), el('td', {class: 'num'}, r.seed), el('td', {}, r.end_reason),
      el('td', {class: 'num'}, fmt(r.flight_time_s)), el('td', {class: 'num'}, fmt(r.nav_cpu_util_pct)),
      el('td', {}, r.worker_host || r.worker)));
  const pager = el('div', {class: 'pager'},
      el('button', {onclick: () => resultsPager(id, box, Math.max(0, offset - limit), pick)}, 'previous'),
      el('button', {onclick: () => { if (offset + limit < page.total) resultsPager(id, box, offset + limit, pick); }}, 'next'),
      `${page.total ? offset + 1 : 0}–${Math.min(offset + limit, page.total)} of ${page.total}`);
  box.replaceChildren(pager, table(['overlay', 'episode', 'board', 'scenario', 'method', 'seed', 'end', 'flight time s',
                                    'nav CPU %', 'host'], rows));
}
