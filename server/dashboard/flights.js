// One flight (the episode page) and two on one set of charts (the overlay page).
'use strict';

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
  // Only flights in wind or with noisy odometry have these columns (docs/air.md).
  {title: 'wind speed at the vehicle', unit: 'm/s', optional: 'wind_speed',
   columns: [{name: 'wind', of: s => s.wind_speed || []}]},
  {title: 'odometry error', unit: 'm', optional: 'odometry_error',
   columns: [{name: '|estimate - truth|', of: s => s.odometry_error || []}]},
];

// The panels a set of flights has data for: the optional ones when any flight has the column.
function panelsOf(seriesList) {
  return PANELS.filter(p => !p.optional || seriesList.some(s => (s[p.optional] || []).length > 0));
}

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
  const charts = panelsOf([s]).map(p => Plots.timeSeries({
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
  for (const p of panelsOf(results.map(r => r.series))) {
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
