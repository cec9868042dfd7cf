// E-Navi Farm dashboard: one page, hash routes, reads the same JSON API as any script.
// Everything a user or a job spec named (job names, labels, reasons) is put into the page as
// text nodes, never as HTML, so a hostile name shows as the characters it is.
'use strict';

const SVG_NS = 'http://www.w3.org/2000/svg';
const COLORS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#17becf'];
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

function svg(tag, attrs, text) {
  const node = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = String(text);
  return node;
}

function fmt(v, digits) {
  if (v === null || v === undefined || Number.isNaN(v)) return '–';
  if (typeof v !== 'number') return String(v);
  const d = digits === undefined ? (Math.abs(v) >= 100 ? 1 : Math.abs(v) >= 1 ? 2 : 3) : digits;
  return v.toFixed(d);
}

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

function show(...nodes) {
  const main = document.getElementById('main');
  main.replaceChildren(...nodes);
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

// ---------------------------------------------------------------- charts (SVG)

function niceTicks(lo, hi, count) {
  if (!(hi > lo)) { hi = lo + 1; }
  const step0 = (hi - lo) / count;
  const mag = Math.pow(10, Math.floor(Math.log10(step0)));
  const step = [1, 2, 5, 10].map(m => m * mag).find(s => s >= step0);
  const ticks = [];
  for (let t = Math.ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) ticks.push(t);
  return ticks;
}

function frame(title, width, height, xr, yr, ylabel) {
  const m = {l: 52, r: 12, t: 22, b: 28};
  const root = svg('svg', {class: 'chart', width, height, viewBox: `0 0 ${width} ${height}`});
  root.appendChild(svg('text', {x: m.l, y: 14, 'font-weight': 'bold'}, ylabel ? `${title} (${ylabel})` : title));
  const sx = x => m.l + (x - xr[0]) / (xr[1] - xr[0] || 1) * (width - m.l - m.r);
  const sy = y => height - m.b - (y - yr[0]) / (yr[1] - yr[0] || 1) * (height - m.t - m.b);
  for (const t of niceTicks(yr[0], yr[1], 4)) {
    root.appendChild(svg('line', {x1: m.l, x2: width - m.r, y1: sy(t), y2: sy(t), stroke: '#eee'}));
    root.appendChild(svg('text', {x: m.l - 4, y: sy(t) + 4, 'text-anchor': 'end'}, fmt(t)));
  }
  root.appendChild(svg('line', {x1: m.l, x2: m.l, y1: m.t, y2: height - m.b, stroke: '#999'}));
  root.appendChild(svg('line', {x1: m.l, x2: width - m.r, y1: height - m.b, y2: height - m.b, stroke: '#999'}));
  return {root, sx, sy, m, width, height};
}

function range(values, pad) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) { if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }
  if (!Number.isFinite(lo)) return [0, 1];
  if (hi === lo) { hi += Math.abs(hi) * 0.1 || 1; lo -= Math.abs(lo) * 0.1 || 0; }
  const p = (hi - lo) * (pad || 0.05);
  return [lo - p, hi + p];
}

// Time series: lines (optionally steps), event markers on the time axis.
function lineChart({title, series, events, width = 560, height = 180, ylabel, xlabel = 't (s)', xIntegers = false}) {
  const xs = series.flatMap(s => s.x);
  const ys = series.flatMap(s => s.err ? s.y.flatMap((y, k) => [y - (s.err[k] || 0), y + (s.err[k] || 0)]) : s.y);
  const f = frame(title, width, height, range(xs, 0), range(ys), ylabel);
  for (const t of niceTicks(range(xs, 0)[0], range(xs, 0)[1], 6)) {
    if (xIntegers && Math.abs(t - Math.round(t)) > 1e-9) continue;
    f.root.appendChild(svg('text', {x: f.sx(t), y: height - 10, 'text-anchor': 'middle'}, xIntegers ? String(Math.round(t)) : fmt(t)));
  }
  f.root.appendChild(svg('text', {x: width - f.m.r, y: height - 2, 'text-anchor': 'end', fill: '#777'}, xlabel));
  for (const e of events || []) {
    const line = svg('line', {class: 'mark event ' + e.kind, x1: f.sx(e.t), x2: f.sx(e.t), y1: f.m.t,
                              y2: height - f.m.b, stroke: e.kind.includes('collision') ? '#d62728' : '#bbb',
                              'stroke-dasharray': '2,2'});
    line.appendChild(svg('title', {}, `${fmt(e.t)} s ${e.kind} ${e.detail || ''}`));
    f.root.appendChild(line);
  }
  series.forEach((s, i) => {
    let d = '';
    for (let k = 0; k < s.x.length; k++) {
      const x = f.sx(s.x[k]), y = f.sy(s.y[k]);
      if (k === 0) d += `M${x},${y}`;
      else d += s.step ? `H${x}V${y}` : `L${x},${y}`;
    }
    const color = s.color || COLORS[i % COLORS.length];
    f.root.appendChild(svg('path', {class: 'mark', d, fill: 'none', stroke: color, 'stroke-width': 1.5}));
    // Error bars (s.err: half-widths, null where unknown).
    (s.err || []).forEach((e, k) => {
      if (e === null || e === undefined) return;
      const x = f.sx(s.x[k]);
      f.root.appendChild(svg('path', {class: 'mark ci', stroke: color, 'stroke-width': 1,
                                      d: `M${x - 4},${f.sy(s.y[k] + e)}H${x + 4}M${x},${f.sy(s.y[k] + e)}` +
                                         `V${f.sy(s.y[k] - e)}M${x - 4},${f.sy(s.y[k] - e)}H${x + 4}`}));
    });
    f.root.appendChild(svg('text', {x: f.m.l + 8 + 90 * i, y: f.m.t + 10, fill: color}, s.name));
  });
  return f.root;
}

// Spread over seeds: per group (board x scenario) and method, min-max whisker, mean +- std box,
// mean dot.
function spreadChart({title, groups, methods, width = 560, height = 200, ylabel}) {
  const values = groups.flatMap(g => methods.flatMap(m => g.stats[m] ? [g.stats[m].min, g.stats[m].max,
                                                        g.stats[m].mean - g.stats[m].std, g.stats[m].mean + g.stats[m].std] : []));
  const f = frame(title, width, height, [0, groups.length], range(values), ylabel);
  const slot = (width - f.m.l - f.m.r) / Math.max(groups.length, 1);
  groups.forEach((g, gi) => {
    f.root.appendChild(svg('text', {x: f.sx(gi + 0.5), y: height - 10, 'text-anchor': 'middle'}, g.label));
    methods.forEach((m, mi) => {
      const st = g.stats[m];
      if (!st) return;
      const x = f.sx(gi) + slot * (mi + 1) / (methods.length + 1);
      const color = COLORS[mi % COLORS.length];
      f.root.appendChild(svg('line', {class: 'mark', x1: x, x2: x, y1: f.sy(st.min), y2: f.sy(st.max), stroke: color}));
      const top = f.sy(st.mean + st.std), bottom = f.sy(st.mean - st.std);
      f.root.appendChild(svg('rect', {class: 'mark', x: x - 5, width: 10, y: top, height: Math.max(1, bottom - top),
                                      fill: color, 'fill-opacity': 0.3, stroke: color}));
      const dot = svg('circle', {class: 'mark', cx: x, cy: f.sy(st.mean), r: 3, fill: color});
      dot.appendChild(svg('title', {}, `${m} ${g.label}: mean ${fmt(st.mean)}, std ${fmt(st.std)}, ` +
                                       `min ${fmt(st.min)}, max ${fmt(st.max)}, n ${st.n}`));
      f.root.appendChild(dot);
    });
  });
  methods.forEach((m, mi) => f.root.appendChild(
      svg('text', {x: f.m.l + 8 + 90 * mi, y: f.m.t + 10, fill: COLORS[mi % COLORS.length]}, m)));
  return f.root;
}

// Two flights from above, on the same axes.
function pathsChart({title, paths, width = 420, height = 420}) {
  const xs = paths.flatMap(p => p.x), ys = paths.flatMap(p => p.y);
  let xr = range(xs), yr = range(ys);
  const span = Math.max(xr[1] - xr[0], yr[1] - yr[0]);  // equal scale on both axes
  xr = [(xr[0] + xr[1] - span) / 2, (xr[0] + xr[1] + span) / 2];
  yr = [(yr[0] + yr[1] - span) / 2, (yr[0] + yr[1] + span) / 2];
  const f = frame(title, width, height, xr, yr);
  paths.forEach((p, i) => {
    const d = p.x.map((x, k) => (k ? 'L' : 'M') + f.sx(x) + ',' + f.sy(p.y[k])).join('');
    f.root.appendChild(svg('path', {class: 'mark', d, fill: 'none', stroke: p.color || COLORS[i], 'stroke-width': 2}));
    f.root.appendChild(svg('text', {x: f.m.l + 8 + 160 * i, y: f.m.t + 10, fill: p.color || COLORS[i]}, p.name));
  });
  return f.root;
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
  // Charts: per board x scenario, each method's spread over seeds.
  const groupsKey = [...new Set(cells.map(c => c.board + ' ' + c.scenario))];
  const methods = [...new Set(cells.map(c => c.method))];
  const charts = ruled.map(m => spreadChart({
    title: m + (rules[m] && rules[m].success_only ? ' (successful flights)' : '') +
           (rules[m] ? ` — ${rules[m].direction} is better` : ''),
    methods,
    groups: groupsKey.map(g => ({label: g, stats: Object.fromEntries(cells.filter(c => c.board + ' ' + c.scenario === g)
                                                                       .filter(c => statOf(c, m))
                                                                       .map(c => [c.method, statOf(c, m)]))}))
  }));
  const frows = failures.failures.map(f => el('tr', {},
      el('td', {}, f.state === 'failed' ? f.episode_id : link('#/episode/' + f.episode_id, f.episode_id)),
      el('td', {}, f.board), el('td', {}, f.scenario), el('td', {}, f.method), el('td', {class: 'num'}, f.seed),
      el('td', {}, f.state), el('td', {class: 'reason'}, f.reason)));
  const other = rest.map(m => el('tr', {}, el('td', {}, m),
      cells.map(c => el('td', {class: 'num'}, c.metrics[m] ? fmt(c.metrics[m].mean) : '–'))));
  const results = el('div', {id: 'results'});
  show(el('h1', {}, 'Job ', el('span', {class: 'job-name'}, job.name), ' ', el('span', {class: 'muted'}, job.id)),
       el('p', {}, labelsOf(job.labels), ' ', job.state, ' ', progressBar(job), ` ${job.done}/${job.total} done`,
          job.failed ? `, ${job.failed} failed` : '', job.state === 'running' ? `, ETA ${duration(job.eta_s)}` : ''),
       el('p', {class: 'muted'}, provenanceText(job.provenance || {})),
       el('h2', {}, 'Summary'), table(header, rows),
       el('h2', {}, 'Spread over seeds'), el('div', {class: 'charts'}, charts),
       el('h2', {}, 'Failures and unsuccessful flights'),
       frows.length ? table(['episode', 'board', 'scenario', 'method', 'seed', 'state', 'reason'], frows)
                    : el('p', {class: 'muted'}, 'none'),
       el('h2', {}, 'Episodes'), results,
       el('h2', {}, 'Other metrics (mean)'),
       table(['metric'].concat(cells.map(c => `${c.board} ${c.scenario} ${c.method}`)), other));
  await resultsPager(id, results, 0);
  if (job.state === 'running') timer = setTimeout(route, 3000);
}

async function resultsPager(id, box, offset) {
  const limit = 50;
  const page = await api(`/api/jobs/${id}/results?offset=${offset}&limit=${limit}`);
  const rows = page.results.map(r => el('tr', {},
      el('td', {}, link('#/episode/' + r.episode_id, r.episode_id)), el('td', {}, r.board), el('td', {}, r.scenario),
      el('td', {}, r.method), el('td', {class: 'num'}, r.seed), el('td', {}, r.end_reason),
      el('td', {class: 'num'}, fmt(r.flight_time_s)), el('td', {class: 'num'}, fmt(r.nav_cpu_util_pct)),
      el('td', {}, r.worker_host || r.worker)));
  const pager = el('div', {class: 'pager'},
      el('button', {onclick: () => resultsPager(id, box, Math.max(0, offset - limit))}, 'previous'),
      el('button', {onclick: () => { if (offset + limit < page.total) resultsPager(id, box, offset + limit); }}, 'next'),
      `${page.total ? offset + 1 : 0}–${Math.min(offset + limit, page.total)} of ${page.total}`);
  box.replaceChildren(pager, table(['episode', 'board', 'scenario', 'method', 'seed', 'end', 'flight time s',
                                    'nav CPU %', 'host'], rows));
}

function speedOf(series) {
  return series.velocity.map(v => Math.hypot(v[0], v[1], v[2]));
}

async function episodePage(id) {
  const r = await api('/api/episodes/' + id + '/result');
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
  const charts = [
    lineChart({title: 'speed', ylabel: 'm/s', series: [{name: '|v|', x: s.t, y: speedOf(s)}], events}),
    lineChart({title: 'navigation CPU', ylabel: '% of a core', series: [{name: 'nav', x: s.t, y: s.utilisation}], events}),
    lineChart({title: 'eci', series: [{name: 'eci', x: s.t, y: s.eci}], events}),
    lineChart({title: 'task frequencies', ylabel: 'Hz', events, series: [
      {name: 'f_per', x: s.t, y: s.f_per, step: true}, {name: 'f_col', x: s.t, y: s.f_col, step: true},
      {name: 'f_dif', x: s.t, y: s.f_dif, step: true}]}),
    lineChart({title: 'map resolution', ylabel: 'm', series: [{name: 'res', x: s.t, y: s.res, step: true}], events}),
  ];
  const evRows = events.slice(0, 300).map(e => el('tr', {}, el('td', {class: 'num'}, fmt(e.t)), el('td', {}, e.kind),
                                                  el('td', {}, e.detail)));
  show(el('h1', {}, 'Episode ', id),
       table(facts.map(f => f[0]), [el('tr', {}, facts.map(f => el('td', {}, f[1])))]),
       notes.length ? table(['provenance', 'value'], notes.map(([k, v]) => el('tr', {}, el('td', {}, k.slice(11)), el('td', {}, v))))
                    : el('p', {class: 'muted'}, 'no provenance notes in this result'),
       el('h2', {}, 'Bird\'s-eye view (path coloured by eci)'), imgBox,
       el('h2', {}, 'Over time (dashed lines: events)'), el('div', {class: 'charts'}, charts),
       el('h2', {}, 'Events'), table(['t s', 'kind', 'detail'], evRows));
}

const VERDICT_RANK = {regression: 4, improvement: 3, change: 2, insignificant: 1, too_few_pairs: 1, same: 0};
const COMPARE_MODES = [['auto', 'auto mode'], ['exact', 'exact mode'], ['paired', 'paired mode (95 % CI)']];

// What the verdicts of this mode can and cannot tell. Flights fork on sub-micrometre differences,
// so on the virtual clock a changed build changes many flights that are no better or worse: an
// exact difference over a few seeds can be a draw, which only the paired test weighs.
function modeNote(report, base, cand) {
  const pairs = report.cells.map(c => c.pairs);
  const seeds = pairs.length ? (Math.min(...pairs) === Math.max(...pairs) ? `${pairs[0]}`
                                                                          : `${Math.min(...pairs)}-${Math.max(...pairs)}`) : '0';
  const paired = `#/compare?base=${encodeURIComponent(base)}&candidate=${encodeURIComponent(cand)}&mode=paired`;
  if (report.mode === 'exact') {
    if (report.changed_metrics === 0) return el('p', {id: 'mode-note', class: 'muted'}, 'exact mode: the same results to the last digit');
    return el('p', {id: 'mode-note', class: 'note'},
              `exact mode: every difference is real, but flights fork on tiny differences, so with ${seeds} seeds a ` +
              'cell can change by the draw of its routes alone' +
              (report.regressions ? ` (${report.regressions_within_draw} of the ${report.regressions} regressions have a ` +
                                    'paired 95 % interval that includes 0). ' : '. '),
              el('a', {href: paired}, 'judge the same jobs in paired mode'),
              ': a change is called only when its 95 % confidence interval over the seeds excludes zero.');
  }
  return el('p', {id: 'mode-note', class: 'muted'},
            `paired mode: ${seeds} seed pairs per cell; a change is called only when the 95 % confidence interval ` +
            'of its mean difference excludes zero (fewer than 2 pairs: too few to judge)');
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
      for (const c of cells) for (const m of c.metrics) if (VERDICT_RANK[m.verdict] > VERDICT_RANK[worst]) worst = m.verdict;
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
       el('p', {class: 'verdict'}, `${report.mode} mode: ${report.regressions} regressions, ${report.improvements} improvements, ` +
          `${report.changed_metrics} changed metrics` + (report.no_change ? ' — no change' : '')),
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
  let pair = null;
  for (const c of cells) {
    const rows = c.metrics.filter(m => m.verdict !== 'same').map(m => el('tr', {class: m.verdict},
        el('td', {}, m.name), el('td', {}, m.verdict + (m.within_draw ? ' (within the draw)' : '')),
        el('td', {class: 'num'}, fmt(m.base_mean)),
        el('td', {class: 'num'}, fmt(m.candidate_mean)), el('td', {class: 'num'}, fmt(m.delta)),
        el('td', {class: 'num'}, `[${fmt(m.ci_low)}, ${fmt(m.ci_high)}]`), el('td', {class: 'num'}, fmt(m.threshold)),
        el('td', {class: 'num'}, m.pairs)));
    blocks.push(el('h2', {}, `${c.board} ${c.scenario} ${c.method}`),
                rows.length ? table(['metric', 'verdict', 'base', 'candidate', 'delta', '95% CI', 'threshold', 'pairs'], rows)
                            : el('p', {class: 'muted'}, 'no change'));
    if (!pair) {
      const changed = c.changed_episodes[0];
      pair = changed ? [changed.base_episode, changed.candidate_episode, changed.seed, c]
                     : [c.base_episodes[0], c.candidate_episodes[0], c.seeds[0], c];
    }
  }
  box.replaceChildren(...blocks, el('p', {}, 'loading flights…'));
  const [a, b] = await Promise.all([api(`/api/episodes/${pair[0]}/result`), api(`/api/episodes/${pair[1]}/result`)]);
  const p = r => ({x: r.series.position.map(q => q[0]), y: r.series.position.map(q => q[1])});
  box.replaceChildren(...blocks,
      el('h2', {}, `Both flights: ${pair[3].board} ${pair[3].scenario} ${pair[3].method} seed ${pair[2]}`),
      el('div', {class: 'charts'},
         pathsChart({title: 'paths from above (x, y m)', paths: [{name: 'base ' + pair[0], ...p(a)},
                                                               {name: 'candidate ' + pair[1], ...p(b)}]}),
         lineChart({title: 'speed', ylabel: 'm/s', series: [{name: 'base', x: a.series.t, y: speedOf(a.series)},
                                                            {name: 'candidate', x: b.series.t, y: speedOf(b.series)}]})));
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
  const series = boards.map(b => {
    const pts = points.filter(p => p.board === b);
    return {name: b, x: pts.map(p => jobIds.indexOf(p.job_id) + 1), y: pts.map(p => p.mean), err: pts.map(p => p.ci95)};
  });
  const cellText = q => q ? fmt(q.mean) + (q.ci95 === null ? '' : ` ± ${fmt(q.ci95)}`) : '–';
  const rows = jobIds.map((id, i) => {
    const pts = points.filter(p => p.job_id === id);
    return el('tr', {}, el('td', {class: 'num'}, i + 1), el('td', {}, link('#/job/' + id, id)),
              el('td', {class: 'job-name'}, pts[0].name),
              el('td', {}, new Date(pts[0].created_ms).toISOString().replace('T', ' ').slice(0, 19)),
              boards.map(b => el('td', {class: 'num'}, cellText(pts.find(p => p.board === b)))));
  });
  show(el('h1', {}, 'Trend'), form,
       points.length ? lineChart({title: `${metric} per board, ${method}, jobs with ${label}`, series, xlabel: 'job #',
                                  xIntegers: true, width: 760, height: 260})
                     : el('p', {class: 'muted'}, 'no results with this label and metric'),
       points.length ? el('p', {id: 'trend-note', class: 'muted'},
                          'bars: 95 % interval of each mean over the seeds\' draw (the spread over seeds within each ' +
                          'scenario, pooled); a step smaller than the bars can be the draw: judge two jobs with compare ' +
                          'in paired mode') : '',
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
