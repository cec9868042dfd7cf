// A label series over time: one metric per job and board, one method at a time.
'use strict';

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
                                        labels, points: chartPoints,
                                        range: (info.metric_rules[metric] || {}).range})
                     : el('p', {class: 'muted'}, 'no results with this label and metric'),
       points.length ? el('p', {id: 'trend-note', class: 'muted'},
                          'bars: 95 % interval of each mean over the seeds\' draw (the spread over seeds within each ' +
                          'scenario, pooled); a step smaller than the bars can be the draw: judge two jobs with compare ' +
                          'in paired mode; drag across the chart to zoom to a range of jobs, double-click to zoom out') : '',
       table(['#', 'job', 'name', 'created (UTC)'].concat(boards), rows));
}
