// E-Navi Farm dashboard: one page, hash routes, reads the same JSON API as any script; the
// charts are plots.js's (Chart.js). Everything a user or a job spec named (job names, labels,
// reasons, methods) is put into the page as text nodes, never as HTML, so a hostile name shows as
// the characters it is.
'use strict';

let info = {metric_rules: {}};
let timer = null;

// ---------------------------------------------------------------- DOM helpers

function el(tag, attrs, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === 'onclick' || k === 'onchange' || k === 'onsubmit') node[k] = v;
    else if (k === 'style') Object.assign(node.style, v);  // CSSOM: allowed by the page's CSP
    else node.setAttribute(k, v);
  }
  for (const c of children.flat()) {
    if (c === null || c === undefined) continue;
    node.appendChild(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return node;
}

const fmt = Plots.fmt;

function duration(s) {
  if (s === undefined || s < 0) return '?';
  if (s < 90) return Math.round(s) + ' s';
  if (s < 5400) return Math.round(s / 60) + ' min';
  return (s / 3600).toFixed(1) + ' h';
}

function labelsOf(labels) {
  return Object.entries(labels || {}).map(([k, v]) => el('span', {class: 'label'}, k + '=' + v));
}

function link(href, text) { return el('a', {href}, text); }

async function api(path) {
  const res = await fetch(path, {credentials: 'same-origin'});
  const body = await res.json().catch(() => ({error: 'reply is not JSON (HTTP ' + res.status + ')'}));
  if (!res.ok) throw new Error(body.error || ('HTTP ' + res.status));
  return body;
}

// Replaces box's content, its charts with it: the old ones are destroyed, the new ones drawn.
function fill(box, ...nodes) {
  for (const c of box.querySelectorAll('canvas.chart')) {
    const chart = Chart.getChart(c);
    if (chart) chart.destroy();
  }
  box.replaceChildren(...nodes);
  Plots.mount(box);
}

function show(...nodes) {
  Plots.destroyAll();
  fill(document.getElementById('main'), ...nodes);
}

function showError(e) {
  show(el('p', {class: 'error'}, 'error: ' + e.message));
}

function hashParams() {
  const q = location.hash.indexOf('?');
  return new URLSearchParams(q < 0 ? '' : location.hash.slice(q + 1));
}

// A <select> of [value, text] options with `selected` chosen.
function selectOf(name, options, selected) {
  return el('select', {name}, options.map(([value, text]) => {
    const o = el('option', {value}, text);
    if (value === selected) o.selected = true;
    return o;
  }));
}

function table(headers, rows) {
  return el('table', {}, el('thead', {}, el('tr', {}, headers.map(h => el('th', {}, h)))),
            el('tbody', {}, rows));
}

// ---------------------------------------------------------------- pages

function provenanceText(p) {
  const parts = [];
  if (p.git_commit) parts.push('commit ' + p.git_commit);
  if (p.enavi_version) parts.push('enavi ' + p.enavi_version);
  if (p.clock) parts.push(p.clock + ' clock');
  if (p.cost) parts.push('cost ' + p.cost);
  if (p.policy_sha256) parts.push('policy ' + p.policy_sha256.slice(0, 12));
  return parts.join(', ');
}

function progressBar(j) {
  const pct = n => (100 * n / Math.max(j.total, 1)) + '%';
  return el('span', {class: 'bar', title: `${j.done} done, ${j.failed} failed of ${j.total}`},
            el('span', {class: 'done', style: {left: '0', width: pct(j.done)}}),
            el('span', {class: 'failed', style: {left: pct(j.done), width: pct(j.failed)}}));
}

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
      el('td', {}, progressBar(j), ` ${j.done}/${j.total}`, j.failed ? ` (${j.failed} failed)` : ''),
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
    groups, methods,
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

function speedOf(series) {
  return series.velocity.map(v => Math.hypot(v[0], v[1], v[2]));
}

// A flight's time series as the episode and overlay pages chart them: a chart per panel, a line
// per column (the overlay: a chart per column, a line per flight).
const PANELS = [
  {title: 'speed', unit: 'm/s', columns: [{name: '|v|', of: speedOf}]},
  {title: 'navigation CPU', unit: '% of a core', columns: [{name: 'nav', of: s => s.utilisation}]},
  {title: 'eci', columns: [{name: 'eci', of: s => s.eci}]},
  {title: 'task frequencies', unit: 'Hz', columns: [{name: 'f_per', of: s => s.f_per, step: true},
                                                    {name: 'f_col', of: s => s.f_col, step: true},
                                                    {name: 'f_dif', of: s => s.f_dif, step: true}]},
  {title: 'map resolution', unit: 'm', columns: [{name: 'res', of: s => s.res, step: true}]},
];

const ZOOM_HINT = 'drag across a chart to zoom in time (the flight\'s other charts follow), double-click to zoom out; ' +
                  'hover for the values';

// The job an episode belongs to: episode ids are JOB-INDEX.
function jobOfEpisode(id) { return id.replace(/-[0-9]+$/, ''); }

// Another flight to overlay on this one: the same board and world in this job, the same seed
// first (the other methods' flight: baseline vs E-Navi), or any episode id typed (another job's:
// before vs after a commit).
function overlayChooser(id, r, episodes) {
  const others = episodes.filter(e => e.id !== id && e.state === 'done' && e.board === r.spec.board && e.world === r.spec.world)
                         .sort((p, q) => (p.seed !== r.spec.seed) - (q.seed !== r.spec.seed) || p.seed - q.seed ||
                                         String(p.method).localeCompare(q.method));
  const pick = selectOf('b', others.map(e => [e.id, `${e.method} seed ${e.seed} (${e.id})`]), others.length ? others[0].id : '');
  const typed = el('input', {type: 'text', name: 'other', placeholder: 'or any episode id'});
  return el('form', {id: 'overlay-with', class: 'inline', onsubmit: ev => {
    ev.preventDefault();
    const b = typed.value.trim() || pick.value;
    if (b) location.hash = `#/overlay?a=${encodeURIComponent(id)}&b=${encodeURIComponent(b)}`;
  }}, 'overlay with', others.length ? pick : '', typed, el('button', {type: 'submit'}, 'overlay'));
}

async function episodePage(id) {
  const [r, episodes] = await Promise.all([api('/api/episodes/' + id + '/result'),
                                           api(`/api/jobs/${jobOfEpisode(id)}/episodes`).catch(() => [])]);
  const s = r.series;
  const events = r.events || [];
  const img = el('img', {class: 'topdown', alt: 'bird\'s-eye view', src: `/api/episodes/${id}/topdown.png`});
  const imgBox = el('div', {}, img);
  img.onerror = () => imgBox.replaceChildren(el('p', {class: 'error'}, 'no bird\'s-eye view: the world could not be rebuilt here'));
  const facts = [['board', r.spec.board], ['scenario', r.scenario], ['method', r.spec.method], ['seed', r.spec.seed],
                 ['clock', r.spec.clock], ['end', r.end_reason], ['flight time s', fmt(r.flight_time_s)],
                 ['path m', fmt(r.path_length_m)], ['nav CPU %', fmt(r.nav_cpu_util_pct)],
                 ['velocity std m/s', fmt(r.velocity_std_mps)], ['deadline misses', r.deadline_misses]];
  const notes = Object.entries(r.notes || {}).filter(([k]) => k.startsWith('provenance.'));
  const charts = PANELS.map(p => Plots.timeSeries({
    title: p.title, unit: p.unit, events, group: 'episode',
    series: p.columns.map(c => ({name: c.name, x: s.t, y: c.of(s), step: c.step}))}));
  const evRows = events.slice(0, 300).map(e => el('tr', {}, el('td', {class: 'num'}, fmt(e.t)), el('td', {}, e.kind),
                                                  el('td', {}, e.detail)));
  show(el('h1', {}, 'Episode ', id),
       table(facts.map(f => f[0]), [el('tr', {}, facts.map(f => el('td', {}, f[1])))]),
       notes.length ? table(['provenance', 'value'], notes.map(([k, v]) => el('tr', {}, el('td', {}, k.slice(11)), el('td', {}, v))))
                    : el('p', {class: 'muted'}, 'no provenance notes in this result'),
       overlayChooser(id, r, episodes),
       el('h2', {}, 'Bird\'s-eye view (path coloured by eci)'), imgBox,
       el('h2', {}, 'Over time (dashed lines: events)'), el('p', {class: 'muted'}, ZOOM_HINT),
       el('div', {class: 'charts'}, charts),
       el('h2', {}, 'Events'), table(['t s', 'kind', 'detail'], evRows));
}

// What tells two flights apart in a legend: what differs between them of job, method, board,
// world and seed.
function flightNames(ids, results) {
  const fields = [['job', (r, id) => jobOfEpisode(id)], ['method', r => r.spec.method], ['board', r => r.spec.board],
                  ['world', r => r.spec.world], ['seed', r => 'seed ' + r.spec.seed]];
  const differ = fields.filter(([, f]) => f(results[0], ids[0]) !== f(results[1], ids[1]));
  const used = differ.length ? differ : fields.slice(1);
  return results.map((r, i) => ['A', 'B'][i] + ': ' + used.map(([, f]) => f(r, ids[i])).join(' '));
}

function pathOf(r) {
  return {x: r.series.position.map(q => q[0]), y: r.series.position.map(q => q[1]), t: r.series.t};
}

// The second flight of an overlay is dashed: where the two are the same, both stay visible.
const FLIGHT_DASH = [[], [6, 3]];

// Two flights on one set of charts: paths from above and every time series, A and B.
function overlayCharts(ids, results, group) {
  const names = flightNames(ids, results);
  const charts = [Plots.paths({title: 'paths from above',
                               paths: results.map((r, i) => ({name: names[i], dash: FLIGHT_DASH[i], ...pathOf(r)}))})];
  for (const p of PANELS) {
    for (const c of p.columns) {
      charts.push(Plots.timeSeries({
        title: p.columns.length > 1 ? `${p.title}: ${c.name}` : p.title, unit: p.unit, group,
        series: results.map((r, i) => ({name: names[i], x: r.series.t, y: c.of(r.series), step: c.step, dash: FLIGHT_DASH[i]}))}));
    }
  }
  return charts;
}

async function overlayPage() {
  const params = hashParams();
  const ids = [params.get('a') || '', params.get('b') || ''];
  const inputs = ids.map((v, i) => el('input', {type: 'text', name: ['a', 'b'][i], value: v, placeholder: 'episode id'}));
  const form = el('form', {class: 'inline', onsubmit: ev => {
    ev.preventDefault();
    location.hash = `#/overlay?a=${encodeURIComponent(inputs[0].value.trim())}&b=${encodeURIComponent(inputs[1].value.trim())}`;
  }}, 'A', inputs[0], 'B', inputs[1], el('button', {type: 'submit'}, 'overlay'));
  if (!ids[0] || !ids[1]) {
    show(el('h1', {}, 'Overlay'), form,
         el('p', {class: 'muted'}, 'two flights on one set of charts: tick two episodes on a job page, use "overlay with" on ' +
                                   'an episode page, or a pair of a compare cell'));
    return;
  }
  const results = await Promise.all(ids.map(id => api('/api/episodes/' + encodeURIComponent(id) + '/result')));
  const names = flightNames(ids, results);
  const rows = results.map((r, i) => el('tr', {},
      el('td', {}, names[i]), el('td', {}, link('#/episode/' + ids[i], ids[i])),
      el('td', {}, link('#/job/' + jobOfEpisode(ids[i]), jobOfEpisode(ids[i]))),
      el('td', {}, r.spec.board), el('td', {}, r.scenario), el('td', {}, r.spec.method), el('td', {class: 'num'}, r.spec.seed),
      el('td', {}, r.end_reason), el('td', {class: 'num'}, fmt(r.flight_time_s)), el('td', {class: 'num'}, fmt(r.path_length_m)),
      el('td', {class: 'num'}, fmt(r.nav_cpu_util_pct))));
  show(el('h1', {}, 'Overlay'), form,
       table(['flight', 'episode', 'job', 'board', 'scenario', 'method', 'seed', 'end', 'flight time s', 'path m', 'nav CPU %'], rows),
       el('p', {class: 'muted'}, ZOOM_HINT + '; drag a box on the paths to zoom there'),
       el('div', {class: 'charts'}, overlayCharts(ids, results, 'overlay')));
}

// A cell's colour: its worst metric. `undecided`: worse beyond the threshold in a cell of one
// seed pair, paired mode (the metric's verdict is too_few_pairs): neither a regression nor fine.
const VERDICT_RANK = {regression: 5, undecided: 4, improvement: 3, change: 2, insignificant: 1, too_few_pairs: 1, same: 0};
const COMPARE_MODES = [['auto', 'auto mode'], ['exact', 'exact mode'], ['paired', 'paired mode (95 % CI)']];
const REPORT_VERDICTS = {regression: 'REGRESSION', cannot_judge: 'CANNOT JUDGE', no_regression: 'no regression',
                         no_change: 'no change'};

function compareHash(base, cand, mode) {
  return `#/compare?base=${encodeURIComponent(base)}&candidate=${encodeURIComponent(cand)}&mode=${mode}`;
}

// What the verdicts of this mode can and cannot tell. Flights fork on sub-micrometre differences,
// so on the virtual clock a changed build changes many flights that are no better or worse: an
// exact difference over a few seeds can be a draw, which only the paired test weighs; with one
// seed pair in a cell there is no interval at all.
function modeNote(report, base, cand) {
  const pairs = report.cells.map(c => c.pairs);
  const seeds = pairs.length ? (Math.min(...pairs) === Math.max(...pairs) ? `${pairs[0]}`
                                                                          : `${Math.min(...pairs)}-${Math.max(...pairs)}`) : '0';
  if (report.mode === 'exact') {
    if (report.changed_metrics === 0) return el('p', {id: 'mode-note', class: 'muted'}, 'exact mode: the same results to the last digit');
    const regs = report.regressions, without = report.regressions_without_interval || 0, withInterval = regs - without;
    const counts = [];
    if (withInterval > 0) {
      counts.push(`${report.regressions_within_draw} of the ${withInterval} regressions with a paired 95 % interval have ` +
                  'one that includes 0');
    }
    if (without > 0) {
      counts.push(`${without} of the ${regs} are in cells of one seed pair: no interval, so whether the seeds' draw alone ` +
                  'gives them cannot be told');
    }
    return el('p', {id: 'mode-note', class: 'note'},
              `exact mode: every difference is real, but flights fork on tiny differences, so with ${seeds} seeds a ` +
              'cell can change by the draw of its routes alone' + (counts.length ? ` (${counts.join('; ')}). ` : '. '),
              el('a', {href: compareHash(base, cand, 'paired')}, 'judge the same jobs in paired mode'),
              ': a change is called only when its 95 % confidence interval over the seeds excludes zero.');
  }
  return el('p', {id: 'mode-note', class: 'muted'},
            `paired mode: ${seeds} seed pairs per cell; a change is called only when the 95 % confidence interval ` +
            'of its mean difference excludes zero (fewer than 2 pairs: too few to judge)');
}

// Paired mode with one seed pair in a cell cannot call a change beyond its threshold either way.
function cannotJudgeNote(report, base, cand) {
  if (report.verdict !== 'cannot_judge') return '';
  return el('p', {id: 'cannot-judge', class: 'note cannot-judge'},
            `CANNOT JUDGE: ${report.undecided} metric(s) in ${report.undecided_cells} cell(s) got worse beyond their ` +
            'threshold, but paired mode needs 2 or more seed pairs per cell for a 95 % interval and these cells have 1: ' +
            'fly 2 or more seeds', report.exact_applies ? [', or ', el('a', {href: compareHash(base, cand, 'exact')},
                                                                        'compare the same jobs in exact mode')] : '', '.');
}

// How the two jobs differ (spec settings per cell, labels, server build): what a change of the
// metrics below may come from, so it comes first.
function specChanges(report) {
  const changes = report.spec_changes || [];
  const rows = changes.map(ch => el('tr', {'data-name': ch.name, 'data-kind': ch.kind},
      el('td', {}, ch.name), el('td', {}, ch.kind),
      el('td', {class: 'num'}, ch.kind === 'spec' ? `${ch.cells} of ${report.spec_cells}` : 'whole job'),
      el('td', {}, ch.base_values.join(', ')), el('td', {}, ch.candidate_values.join(', '))));
  let body;
  if (rows.length) {
    body = table(['setting', 'kind', 'cells', 'base', 'candidate'], rows);
  } else if (report.specs_compared && report.jobs_compared) {
    body = el('p', {class: 'muted'}, 'the two jobs\' specs, labels and server builds are the same');
  } else {
    body = el('p', {class: 'note'}, 'not known for ' + [report.specs_compared ? '' : 'the episodes\' specs',
                                                      report.jobs_compared ? '' : 'the jobs\' labels and builds']
                                                         .filter(Boolean).join(' and ') + ': whether they differ cannot be told');
  }
  return el('div', {id: 'spec-changes'}, el('h2', {}, 'How the jobs differ'), body);
}

async function comparePage() {
  const params = hashParams();
  const jobs = await api('/api/jobs');
  const pick = (name, value) => selectOf(name, jobs.map(j => [j.id, `${j.id} ${j.name}`]), value);
  let base = params.get('base'), cand = params.get('candidate');
  const series = params.get('label');
  const mode = params.get('mode') || 'auto';
  if (series && (!base || !cand)) {
    const matching = await api('/api/jobs?label=' + encodeURIComponent(series));
    if (matching.length >= 2) { base = matching[matching.length - 2].id; cand = matching[matching.length - 1].id; }
  }
  const baseSel = pick('base', base), candSel = pick('candidate', cand);
  const labelIn = el('input', {type: 'text', placeholder: 'or a label series: suite=nightly', value: series || ''});
  const modeSel = selectOf('mode', COMPARE_MODES, mode);
  const form = el('form', {class: 'inline', onsubmit: ev => {
    ev.preventDefault();
    location.hash = (labelIn.value.trim() && labelIn.value.trim() !== (series || '')
      ? '#/compare?label=' + encodeURIComponent(labelIn.value.trim())
      : `#/compare?base=${baseSel.value}&candidate=${candSel.value}`) + `&mode=${modeSel.value}`;
  }}, 'base', baseSel, 'candidate', candSel, labelIn, modeSel, el('button', {type: 'submit'}, 'compare'));
  if (!base || !cand) {
    show(el('h1', {}, 'Compare'), form, el('p', {class: 'muted'}, 'pick two jobs (or a label series: its last two jobs)'));
    return;
  }
  const report = await api(`/api/compare?base=${encodeURIComponent(base)}&candidate=${encodeURIComponent(cand)}` +
                           `&mode=${encodeURIComponent(mode)}`);
  const boards = [...new Set(report.cells.map(c => c.board))];
  const scenarios = [...new Set(report.cells.map(c => c.scenario))];
  const detail = el('div', {id: 'detail'});
  const matrix = table(['board \\ scenario'].concat(scenarios), boards.map(b => el('tr', {}, el('th', {}, b),
    scenarios.map(sc => {
      const cells = report.cells.filter(c => c.board === b && c.scenario === sc);
      if (!cells.length) return el('td', {class: 'muted'}, '–');
      let worst = 'same';
      for (const c of cells) {
        for (const m of c.metrics) {
          const v = m.undecided ? 'undecided' : m.verdict;
          if (VERDICT_RANK[v] > VERDICT_RANK[worst]) worst = v;
        }
      }
      const summary = cells.map(c => `${c.method}: ${c.regressions} worse, ${c.improvements} better`);
      const td = el('td', {class: 'cell ' + worst, 'data-board': b, 'data-scenario': sc, 'data-verdict': worst},
                    el('b', {}, worst), summary.map(t => el('div', {}, t)));
      td.onclick = () => {
        document.querySelectorAll('td.cell').forEach(n => n.classList.remove('selected'));
        td.classList.add('selected');
        cellDetail(cells, detail);
      };
      return td;
    }))));
  // What changed besides the code: another cost model re-prices CPU and timing.
  const provenance = (report.provenance || []).map(p => el('tr', {'data-name': p.name}, el('td', {}, p.name),
      el('td', {class: 'num'}, `${p.cells} of ${report.cells.length}`), el('td', {}, p.base_values.join(', ')),
      el('td', {}, p.candidate_values.join(', ')), el('td', {}, p.meaning)));
  const unpaired = report.unpaired.map(u => el('tr', {}, el('td', {}, u.side), el('td', {}, u.board),
      el('td', {}, u.scenario), el('td', {}, u.method), el('td', {class: 'num'}, u.seed)));
  show(el('h1', {}, 'Compare'), form,
       specChanges(report),
       el('h2', {}, 'Metrics'),
       el('p', {class: 'verdict verdict-' + report.verdict, 'data-verdict': report.verdict},
          el('b', {}, REPORT_VERDICTS[report.verdict] || report.verdict), ` — ${report.mode} mode: ${report.regressions} regressions, ` +
          `${report.improvements} improvements, ${report.changed_metrics} changed metrics`),
       cannotJudgeNote(report, base, cand),
       modeNote(report, base, cand),
       provenance.length ? el('div', {id: 'provenance'}, el('h2', {}, 'Provenance that differs'),
                              table(['note', 'cells', 'base', 'candidate', 'meaning'], provenance)) : '',
       matrix, el('p', {class: 'muted'}, 'click a cell for its metrics and both flights'),
       unpaired.length ? el('div', {}, el('h2', {}, 'Unpaired (in one job only)'),
                            table(['only in', 'board', 'scenario', 'method', 'seed'], unpaired)) : '',
       detail);
}

async function cellDetail(cells, box) {
  const blocks = [];
  for (const c of cells) {
    const rows = c.metrics.filter(m => m.verdict !== 'same').map(m => el('tr', {class: m.undecided ? 'undecided' : m.verdict},
        el('td', {}, m.name),
        el('td', {}, m.verdict + (m.within_draw ? ' (within the draw)' : '') + (m.undecided ? ' (worse: cannot judge)' : '')),
        el('td', {class: 'num'}, fmt(m.base_mean)),
        el('td', {class: 'num'}, fmt(m.candidate_mean)), el('td', {class: 'num'}, fmt(m.delta)),
        el('td', {class: 'num'}, m.has_interval === false ? 'no interval' : `[${fmt(m.ci_low)}, ${fmt(m.ci_high)}]`),
        el('td', {class: 'num'}, fmt(m.threshold)), el('td', {class: 'num'}, m.pairs)));
    // Every seed pair opens as an overlay of its two flights.
    const pairLinks = c.seeds.map((seed, i) => link(
        `#/overlay?a=${encodeURIComponent(c.base_episodes[i])}&b=${encodeURIComponent(c.candidate_episodes[i])}`, `seed ${seed}`));
    blocks.push(el('h2', {}, `${c.board} ${c.scenario} ${c.method}`),
                rows.length ? table(['metric', 'verdict', 'base', 'candidate', 'delta', '95% CI', 'threshold', 'pairs'], rows)
                            : el('p', {class: 'muted'}, 'no change'),
                el('p', {class: 'pairs'}, 'overlay both flights of ', pairLinks.flatMap((l, i) => (i ? [', ', l] : [l]))));
  }
  // The flights shown: a changed pair of the method that regressed most (else of the first).
  const worst = cells.reduce((w, c) => (c.regressions > w.regressions ? c : w), cells[0]);
  const changed = worst.changed_episodes[0];
  const pair = changed ? [changed.base_episode, changed.candidate_episode, changed.seed, worst]
                       : [worst.base_episodes[0], worst.candidate_episodes[0], worst.seeds[0], worst];
  fill(box, ...blocks, el('p', {}, 'loading flights…'));
  const [a, b] = await Promise.all([api(`/api/episodes/${pair[0]}/result`), api(`/api/episodes/${pair[1]}/result`)]);
  const names = ['base ' + pair[0], 'candidate ' + pair[1]];
  fill(box, ...blocks,
      el('h2', {}, `Both flights: ${pair[3].board} ${pair[3].scenario} ${pair[3].method} seed ${pair[2]} `,
         link(`#/overlay?a=${encodeURIComponent(pair[0])}&b=${encodeURIComponent(pair[1])}`, '(every chart)')),
      el('div', {class: 'charts'},
         Plots.paths({title: 'paths from above', paths: [{name: names[0], ...pathOf(a)},
                                                         {name: names[1], dash: FLIGHT_DASH[1], ...pathOf(b)}]}),
         Plots.timeSeries({title: 'speed', unit: 'm/s', series: [
           {name: names[0], x: a.series.t, y: speedOf(a.series)},
           {name: names[1], x: b.series.t, y: speedOf(b.series), dash: FLIGHT_DASH[1]}]})));
}

async function trendPage() {
  const params = hashParams();
  const label = params.get('label') || '';
  const metric = params.get('metric') || 'flight_time_s';
  const labelIn = el('input', {type: 'text', placeholder: 'suite=nightly', value: label});
  const metricIn = el('input', {type: 'text', value: metric});
  const trend = label ? await api(`/api/trend?label=${encodeURIComponent(label)}&metric=${encodeURIComponent(metric)}&limit=1000`)
                      : {points: []};
  // One method at a time: the stacks differ by more than any commit moves one of them.
  const methods = [...new Set(trend.points.map(p => p.method))].sort();
  const method = methods.includes(params.get('method')) ? params.get('method') : methods[0];
  const methodSel = selectOf('method', methods.map(m => [m, m]), method);
  const form = el('form', {class: 'inline', onsubmit: ev => {
    ev.preventDefault();
    location.hash = `#/trend?label=${encodeURIComponent(labelIn.value.trim())}&metric=${encodeURIComponent(metricIn.value.trim())}` +
                    (methodSel.value ? `&method=${encodeURIComponent(methodSel.value)}` : '');
  }}, 'label', labelIn, 'metric', metricIn, methods.length ? 'method' : '', methods.length ? methodSel : '',
     el('button', {type: 'submit'}, 'show'));
  if (!label) {
    show(el('h1', {}, 'Trend'), form, el('p', {class: 'muted'}, 'a label series (e.g. suite=nightly) over time, per board'));
    return;
  }
  const points = trend.points.filter(p => p.method === method);
  const jobIds = [...new Set(points.map(p => p.job_id))];
  const boards = [...new Set(points.map(p => p.board))];
  const labels = jobIds.map((id, i) => `#${i + 1} ${points.find(p => p.job_id === id).name} (${id})`);
  const chartPoints = points.map(p => ({series: p.board, x: jobIds.indexOf(p.job_id) + 1, mean: p.mean, ci95: p.ci95,
                                        text: `(n ${p.n})`}));
  const cellText = q => q ? fmt(q.mean) + (q.ci95 === null ? '' : ` ± ${fmt(q.ci95)}`) : '–';
  const rows = jobIds.map((id, i) => {
    const pts = points.filter(p => p.job_id === id);
    return el('tr', {}, el('td', {class: 'num'}, i + 1), el('td', {}, link('#/job/' + id, id)),
              el('td', {class: 'job-name'}, pts[0].name),
              el('td', {}, new Date(pts[0].created_ms).toISOString().replace('T', ' ').slice(0, 19)),
              boards.map(b => el('td', {class: 'num'}, cellText(pts.find(p => p.board === b)))));
  });
  show(el('h1', {}, 'Trend'), form,
       points.length ? Plots.jobSeries({title: `${metric} per board, ${method}, jobs with ${label}`, seriesNames: boards,
                                        labels, points: chartPoints})
                     : el('p', {class: 'muted'}, 'no results with this label and metric'),
       points.length ? el('p', {id: 'trend-note', class: 'muted'},
                          'bars: 95 % interval of each mean over the seeds\' draw (the spread over seeds within each ' +
                          'scenario, pooled); a step smaller than the bars can be the draw: judge two jobs with compare ' +
                          'in paired mode; drag across the chart to zoom to a range of jobs, double-click to zoom out') : '',
       table(['#', 'job', 'name', 'created (UTC)'].concat(boards), rows));
}

// ---------------------------------------------------------------- router

async function route() {
  clearTimeout(timer);
  const hash = location.hash;
  delete document.body.dataset.ready;  // tests wait for ready === the hash they opened
  const path = location.hash.replace(/^#/, '').split('?')[0] || '/jobs';
  const parts = path.split('/').filter(Boolean);
  document.body.dataset.page = parts[0] || 'jobs';
  try {
    if (parts[0] === 'job' && parts[1]) await jobPage(parts[1]);
    else if (parts[0] === 'episode' && parts[1]) await episodePage(parts[1]);
    else if (parts[0] === 'overlay') await overlayPage();
    else if (parts[0] === 'compare') await comparePage();
    else if (parts[0] === 'trend') await trendPage();
    else await jobsPage();
    document.body.dataset.ready = hash;
  } catch (e) {
    showError(e);
    document.body.dataset.ready = 'error';
  }
}

window.addEventListener('hashchange', route);
api('/api/info').then(i => {
  info = i;
  document.getElementById('build').textContent =
      `enavi ${i.enavi_version} (${i.git_commit})` + (i.read_only ? ', read-only' : '');
}).catch(() => {}).finally(route);
