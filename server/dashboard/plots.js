// E-Navi Farm dashboard: the charts, built on Chart.js (Debian's libjs-chart.js, embedded in the
// binary at build time and served as /static/chart.min.js). This file only configures the
// library: the three chart kinds the pages need (time series, spread over seeds, paths from
// above), a tooltip mode that reads every series at the cursor's x, and drag-to-zoom.
//
// A builder returns a <canvas> holding its configuration; Plots.mount(root) creates the charts
// once the canvases are in the page (Chart.js sizes a chart from its attached canvas).
'use strict';

const Plots = (() => {
  const COLORS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#17becf'];
  const EVENT_COLOR = '#999', COLLISION_COLOR = '#d62728';
  // mousedown, mouseup and dblclick on top of Chart.js's defaults: the zoom reads them.
  const EVENTS = ['mousemove', 'mouseout', 'click', 'touchstart', 'touchmove', 'mousedown', 'mouseup', 'dblclick'];

  Chart.defaults.animation = false;  // pages and screenshots show the final state at once
  Chart.defaults.font.family = '"DejaVu Sans", sans-serif';
  Chart.defaults.font.size = 11;
  Chart.defaults.color = '#333';

  const color = i => COLORS[i % COLORS.length];

  // A number as the pages print it: 1 decimal from 100, 2 from 1, else 3 (or `digits`).
  function fmt(v, digits) {
    if (v === null || v === undefined || Number.isNaN(v)) return '–';
    if (typeof v !== 'number') return String(v);
    const d = digits === undefined ? (Math.abs(v) >= 100 ? 1 : Math.abs(v) >= 1 ? 2 : 3) : digits;
    return v.toFixed(d);
  }

  // ------------------------------------------------------------ tooltip mode: every series at x

  // For each series, the sample nearest the cursor's x, so one tooltip lists all of them at that
  // time: the two flights of an overlay (their samples need not share times), or every method
  // of a board x scenario group. Elements are in data order, sorted by x. A dataset can limit how
  // far (in x units) a sample may be to be shown (`snap`, e.g. half a group), and opt out
  // (`hoverable: false`: the whiskers and boxes, whose numbers the mean's tooltip already gives).
  Chart.Interaction.modes.eachNearestX = function (chart, e, options, useFinalPosition) {
    const pos = Chart.helpers.getRelativePosition(e, chart);
    if (!chart.isPointInArea(pos)) return [];
    const xScale = chart.scales.x;
    const items = [];
    for (const meta of chart.getSortedVisibleDatasetMetas()) {
      const ds = chart.data.datasets[meta.index];
      const els = meta.data;
      if (ds.hoverable === false || !els.length) continue;
      const xOf = k => els[k].getProps(['x'], useFinalPosition).x;
      let lo = 0, hi = els.length - 1;
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (xOf(mid) < pos.x) lo = mid; else hi = mid;
      }
      // The nearer of the two, stepping over gaps (null values).
      const order = Math.abs(xOf(lo) - pos.x) <= Math.abs(xOf(hi) - pos.x) ? [lo, hi] : [hi, lo];
      let k = order.find(i => !els[i].skip);
      if (k === undefined) {
        for (let d = 1; d < els.length && k === undefined; d++) {
          for (const i of [order[0] - d, order[0] + d]) if (i >= 0 && i < els.length && !els[i].skip) { k = i; break; }
        }
      }
      if (k === undefined) continue;
      // How far from the cursor a sample may be: `snap` in x units, `snapPx` in pixels, else
      // anywhere within the series' extent.
      let limitPx = Infinity;
      if (ds.snap !== undefined) limitPx = Math.abs(xScale.getPixelForValue(ds.snap) - xScale.getPixelForValue(0));
      if (ds.snapPx !== undefined) limitPx = ds.snapPx;
      const edge = Number.isFinite(limitPx) ? limitPx : 4;
      const first = xOf(0), last = xOf(els.length - 1);
      if (pos.x < Math.min(first, last) - edge || pos.x > Math.max(first, last) + edge) continue;
      if (Math.abs(xOf(k) - pos.x) > limitPx) continue;
      items.push({element: els[k], datasetIndex: meta.index, index: k});
    }
    return items;
  };

  // ------------------------------------------------------------ drag to zoom

  // Drag across the plot to zoom to that range (x; x and y at equal scale for paths), double-click
  // to go back. Charts of one `group` (an episode's time series) zoom together, so a moment can be
  // read across speed, CPU, eci and the task rates. The library moves its scales (min/max options).
  const groups = new Map();
  const dragZoom = {
    id: 'dragZoom',
    defaults: {mode: null, group: null},
    afterInit(chart, args, opts) {
      if (opts.group) (groups.get(opts.group) || groups.set(opts.group, new Set()).get(opts.group)).add(chart);
    },
    afterDestroy(chart, args, opts) {
      if (opts.group && groups.has(opts.group)) groups.get(opts.group).delete(chart);
    },
    afterEvent(chart, args, opts) {
      if (!opts.mode) return;
      const e = args.event, a = chart.chartArea, st = chart.$drag || (chart.$drag = {});
      const clamp = p => ({x: Math.min(Math.max(p.x, a.left), a.right), y: Math.min(Math.max(p.y, a.top), a.bottom)});
      if (e.type === 'mousedown' && args.inChartArea) {
        st.from = st.to = clamp(e);
      } else if (e.type === 'mousemove' && st.from) {
        st.to = clamp(e);
        args.changed = true;
      } else if ((e.type === 'mouseup' || e.type === 'mouseout') && st.from) {
        // The library hands on at most one event of a type per frame: the release point is this
        // event's, whatever the last move it passed on.
        const from = st.from, to = clamp(e);
        st.from = null;
        args.changed = true;
        const enough = Math.abs(to.x - from.x) > 4 && (opts.mode === 'x' || Math.abs(to.y - from.y) > 4);
        if (enough) zoomTo(chart, opts, from, to);
      } else if (e.type === 'dblclick') {
        resetZoom(chart, opts);
      }
    },
    afterDraw(chart, args, opts) {
      const st = chart.$drag;
      if (!opts.mode || !st || !st.from) return;
      const a = chart.chartArea, ctx = chart.ctx;
      const x0 = Math.min(st.from.x, st.to.x), x1 = Math.max(st.from.x, st.to.x);
      const y0 = opts.mode === 'x' ? a.top : Math.min(st.from.y, st.to.y);
      const y1 = opts.mode === 'x' ? a.bottom : Math.max(st.from.y, st.to.y);
      ctx.save();
      ctx.fillStyle = 'rgba(31, 59, 87, 0.15)';
      ctx.fillRect(x0, y0, x1 - x0, y1 - y0);
      ctx.restore();
    },
  };
  Chart.register(dragZoom);

  function zoomTo(chart, opts, from, to) {
    const xs = chart.scales.x, ys = chart.scales.y;
    const x = [xs.getValueForPixel(from.x), xs.getValueForPixel(to.x)].sort((p, q) => p - q);
    const members = opts.group ? [...groups.get(opts.group)] : [chart];
    for (const c of members) {
      const o = c.options.scales;
      c.$home = c.$home || {x: [o.x.min, o.x.max], y: [o.y.min, o.y.max]};
      [o.x.min, o.x.max] = x;
      if (opts.mode === 'xy') {
        // Equal scale on both axes (a path from above): widen the narrower span.
        let y = [ys.getValueForPixel(from.y), ys.getValueForPixel(to.y)].sort((p, q) => p - q);
        const perPx = Math.max((x[1] - x[0]) / c.chartArea.width, (y[1] - y[0]) / c.chartArea.height);
        const mx = (x[0] + x[1]) / 2, my = (y[0] + y[1]) / 2;
        [o.x.min, o.x.max] = [mx - perPx * c.chartArea.width / 2, mx + perPx * c.chartArea.width / 2];
        y = [my - perPx * c.chartArea.height / 2, my + perPx * c.chartArea.height / 2];
        [o.y.min, o.y.max] = y;
      }
      c.update('none');
    }
  }

  function resetZoom(chart, opts) {
    const members = opts.group ? [...groups.get(opts.group)] : [chart];
    for (const c of members) {
      if (!c.$home) continue;
      const o = c.options.scales;
      [o.x.min, o.x.max] = c.$home.x;
      [o.y.min, o.y.max] = c.$home.y;
      c.$home = null;
      c.update('none');
    }
  }

  // ------------------------------------------------------------ shared configuration

  // A legend of colour swatches above the plot area (the library lays it out beside the area,
  // never on it), the title above that.
  function baseOptions(title, extra) {
    return {
      responsive: false,
      events: EVENTS,
      plugins: {
        title: {display: true, text: title, align: 'start', font: {weight: 'bold', size: 12}, padding: {top: 2, bottom: 2}},
        legend: {position: 'top', align: 'start', labels: {boxWidth: 14, boxHeight: 8, padding: 8,
                                                            filter: (item, data) => data.datasets[item.datasetIndex].inLegend !== false}},
        tooltip: {},
        dragZoom: {},
      },
      ...extra,
    };
  }

  function canvasFor(config, width, height, kind) {
    const c = document.createElement('canvas');
    c.className = 'chart ' + kind;
    c.width = width;
    c.height = height;
    c.$config = config;
    return c;
  }

  // Creates the charts of the canvases under root (once each).
  function mount(root) {
    for (const c of root.querySelectorAll('canvas.chart')) {
      if (!c.$config || Chart.getChart(c)) continue;
      const config = c.$config;
      c.$config = null;
      const chart = new Chart(c, config);
      if (config.afterMount) config.afterMount(chart);
    }
  }

  // Destroys every chart (a page is replaced): their zoom groups and listeners go with them.
  function destroyAll() {
    for (const chart of Object.values(Chart.instances)) chart.destroy();
  }

  // ------------------------------------------------------------ a metric's bounds

  // The values a metric can take, from its rule's range (/api/info): an outcome is 0 or 1 per
  // flight, so a cell's mean (a rate) lies in 0..1; a non-negative metric (a count, a time, a
  // ratio) has a floor of 0; any other is unbounded.
  function boundsOf(range) {
    return range === 'outcome' ? {lo: 0, hi: 1} : range === 'non_negative' ? {lo: 0, hi: Infinity}
                                                                             : {lo: -Infinity, hi: Infinity};
  }
  const clampTo = (b, v) => Math.min(Math.max(v, b.lo), b.hi);

  // The y axis of a bounded metric, given the lowest and highest values drawn: an outcome's
  // reads 0..1 with a small pad (the library pads a constant rate of 1 out to -0.5..2.5). One
  // with a floor, if the drawn values come near it or never change (the library would centre a
  // constant in +-1), stops just below the floor instead of reaching into values the metric
  // cannot take: a constant v is drawn up to twice its height above the floor (at the floor: up
  // to one above it). Ticks are the library's round values within the bounds: not the padded
  // ends (includeBounds would put -0.05 in place of 0). Otherwise ({}), the library's own range.
  function boundedAxis(b, lowest, highest) {
    const bounded = (min, max) => ({min, max, grace: 0, ticks: {includeBounds: false},
                                    afterBuildTicks: axis => { axis.ticks = axis.ticks.filter(t => t.value >= b.lo && t.value <= b.hi); }});
    if (Number.isFinite(b.lo) && Number.isFinite(b.hi)) {
      const pad = 0.05 * (b.hi - b.lo);
      return bounded(b.lo - pad, b.hi + pad);
    }
    if (!Number.isFinite(b.lo) || !Number.isFinite(lowest)) return {};
    const constant = highest === lowest;
    if (!constant && lowest - 0.1 * (highest - lowest) > b.lo) return {};
    const top = !constant ? highest + 0.08 * (highest - b.lo) : highest > b.lo ? b.lo + 2 * (highest - b.lo) : b.lo + 1;
    return bounded(b.lo - 0.03 * (top - b.lo), top);
  }

  // ------------------------------------------------------------ time series

  // Vertical dashed lines at the events' times, one dataset per kind (collisions red), on a
  // hidden 0..1 axis: each event is a segment from the bottom to the top of the plot.
  function eventDatasets(events) {
    const kinds = [...new Set(events.map(e => e.kind))];
    return kinds.map(kind => ({
      type: 'line', label: kind, yAxisID: 'yEvents', role: 'event', snapPx: 4,
      borderColor: kind.includes('collision') ? COLLISION_COLOR : EVENT_COLOR, backgroundColor: 'transparent',
      borderWidth: 1, borderDash: [3, 3], pointRadius: 0, spanGaps: false,
      data: events.filter(e => e.kind === kind).flatMap(e => [{x: e.t, y: 0, detail: e.detail}, {x: e.t, y: 1, detail: e.detail},
                                                           {x: e.t, y: null}]),
    }));
  }

  // A series that never changes (a fixed map resolution, a task's constant rate) is drawn
  // between 0 and twice its value; the library would centre it in +-1, whatever its size.
  function constantRange(series) {
    const ys = series.flatMap(s => s.y).filter(Number.isFinite);
    if (!ys.length || ys.some(y => y !== ys[0])) return {};
    const v = ys[0];
    return v > 0 ? {min: 0, max: 2 * v} : v < 0 ? {min: 2 * v, max: 0} : {min: 0, max: 1};
  }

  // series: [{name, x: [], y: [], step, color, dash}]; events: [{t, kind, detail}]; unit of y;
  // group: charts that zoom together.
  function timeSeries({title, series, events = [], unit = '', xlabel = 't (s)', group = null, width = 560, height = 230}) {
    const datasets = series.map((s, i) => ({
      type: 'line', label: s.name, role: 'series',
      borderColor: s.color || color(i), backgroundColor: s.color || color(i),
      borderWidth: 1.5, borderDash: s.dash || [], pointRadius: s.x.length === 1 ? 3 : 0, pointHitRadius: 4,
      stepped: s.step ? 'after' : false,
      data: s.x.map((x, k) => ({x, y: s.y[k]})),
    })).concat(eventDatasets(events));
    const config = {
      type: 'line',
      data: {datasets},
      options: baseOptions(unit ? `${title} (${unit})` : title, {
        interaction: {mode: 'eachNearestX', intersect: false},
        scales: {
          x: {type: 'linear', title: {display: true, text: xlabel}, ticks: {includeBounds: false}},
          y: {type: 'linear', ...constantRange(series)},
          yEvents: {type: 'linear', axis: 'y', display: false, min: 0, max: 1},
        },
      }),
    };
    config.options.plugins.dragZoom = {mode: 'x', group};
    config.options.plugins.tooltip.callbacks = {
      title: items => items.length ? `t = ${fmt(items[0].parsed.x)} s` : '',
      label: item => item.dataset.role === 'event' ? `${item.dataset.label} ${item.raw.detail || ''}`
                                                   : `${item.dataset.label}: ${fmt(item.parsed.y)}${unit ? ' ' + unit : ''}`,
    };
    return canvasFor(config, width, height, 'timeseries');
  }

  // ------------------------------------------------------------ spread over seeds

  // Per group (e.g. board x scenario) and method: a whisker from min to max, a box of mean ± std,
  // and a dot at the mean, side by side in the group's slot. stats(group, method) gives
  // {n, mean, std, min, max} or null; methods are whatever the job flew; range is the metric's
  // (boundsOf).
  function spread({title, groups, methods, stats, range, width = 560, height = 250}) {
    const M = Math.max(methods.length, 1);
    const slot = 0.8 / M;
    const xOf = (gi, mi) => gi + (mi - (M - 1) / 2) * slot;
    // mean ± std is drawn clamped to the metric's bounds: the box of a count that is mostly 0
    // would reach below 0, a value it cannot take (the tooltip still gives the std itself).
    const b = boundsOf(range);
    const box = st => [clampTo(b, st.mean - (st.std || 0)), clampTo(b, st.mean + (st.std || 0))];
    const drawn = methods.flatMap(m => groups.map(g => stats(g, m)).filter(st => st))
                         .flatMap(st => [st.min, st.max, ...box(st)]).filter(Number.isFinite);
    const datasets = [];
    methods.forEach((m, mi) => {
      const c = color(mi);
      const rows = groups.map((g, gi) => ({g, x: xOf(gi, mi), st: stats(g, m)})).filter(r => r.st);
      datasets.push(
          {type: 'bar', label: m + ' min–max', method: m, role: 'whisker', inLegend: false, hoverable: false, grouped: false,
           backgroundColor: c, maxBarThickness: 2, data: rows.map(r => ({x: r.x, y: [r.st.min, r.st.max]}))},
          {type: 'bar', label: m + ' mean ± std', method: m, role: 'box', inLegend: false, hoverable: false, grouped: false,
           backgroundColor: c + '55', borderColor: c, borderWidth: 1, borderSkipped: false, maxBarThickness: 14, minBarLength: 1,
           data: rows.map(r => ({x: r.x, y: box(r.st)}))},
          {type: 'scatter', label: m, method: m, role: 'mean', snap: 0.5, backgroundColor: c, borderColor: '#fff', borderWidth: 1,
           pointRadius: 4, pointHoverRadius: 5,
           data: rows.map(r => ({x: r.x, y: r.st.mean, group: r.g, st: r.st}))});
    });
    const config = {
      type: 'scatter',
      data: {datasets},
      options: baseOptions(title, {
        interaction: {mode: 'eachNearestX', intersect: false},
        scales: {
          x: {type: 'linear', min: -0.5, max: groups.length - 0.5, offset: false, grid: {display: false, offset: false},
              afterBuildTicks: axis => { axis.ticks = groups.map((g, i) => ({value: i})); },
              ticks: {autoSkip: false, maxRotation: 0, callback: v => groups[v] === undefined ? '' : groups[v]}},
          y: {type: 'linear', beginAtZero: false, grace: '8%',
              ...boundedAxis(b, Math.min(...drawn), Math.max(...drawn))},
        },
      }),
    };
    // The legend toggles a method's three datasets together.
    config.options.plugins.legend.onClick = (e, item, legend) => {
      const chart = legend.chart, method = chart.data.datasets[item.datasetIndex].method;
      const hidden = chart.isDatasetVisible(item.datasetIndex);
      chart.data.datasets.forEach((ds, i) => { if (ds.method === method) chart.setDatasetVisibility(i, !hidden); });
      chart.update('none');
    };
    config.options.plugins.tooltip.callbacks = {
      title: items => items.length ? items[0].raw.group : '',
      label: item => {
        const st = item.raw.st;
        return `${item.dataset.label}: mean ${fmt(st.mean)}, std ${fmt(st.std)}, min ${fmt(st.min)}, max ${fmt(st.max)}, n ${st.n}`;
      },
    };
    return canvasFor(config, width, height, 'spread');
  }

  // ------------------------------------------------------------ a series of jobs

  // points: [{series, x (1-based job #), mean, ci95 (half-width or null), text}], a line per
  // series, each mean with a bar of its 95 % interval; labels[x - 1] names job x. Series are
  // nudged apart within a job so their bars do not hide each other; range is the metric's
  // (boundsOf): an interval is drawn clamped to its bounds.
  function jobSeries({title, seriesNames, labels, points, range, width = 760, height = 280}) {
    const b = boundsOf(range);
    const bar = p => [clampTo(b, p.mean - p.ci95), clampTo(b, p.mean + p.ci95)];
    const hasBar = p => p.ci95 !== null && p.ci95 !== undefined;
    const drawn = points.flatMap(p => hasBar(p) ? [p.mean, ...bar(p)] : [p.mean]).filter(Number.isFinite);
    const S = Math.max(seriesNames.length, 1);
    const nudge = i => (i - (S - 1) / 2) * Math.min(0.08, 0.5 / S);
    const datasets = [];
    seriesNames.forEach((name, si) => {
      const c = color(si), pts = points.filter(p => p.series === name).sort((a, b) => a.x - b.x);
      datasets.push(
          {type: 'line', label: name, role: 'mean', snap: 0.5, borderColor: c, backgroundColor: c, borderWidth: 1.5,
           pointRadius: 4, pointHoverRadius: 5,
           data: pts.map(p => ({x: p.x + nudge(si), y: p.mean, ci95: p.ci95, text: p.text}))},
          {type: 'bar', label: name + ' 95 % interval', role: 'ci', inLegend: false, hoverable: false, grouped: false,
           backgroundColor: c, maxBarThickness: 2,
           data: pts.filter(hasBar).map(p => ({x: p.x + nudge(si), y: bar(p)}))});
    });
    const config = {
      type: 'line',
      data: {datasets},
      options: baseOptions(title, {
        interaction: {mode: 'eachNearestX', intersect: false},
        scales: {
          x: {type: 'linear', min: 0.5, max: labels.length + 0.5, offset: false, grid: {offset: false},
              title: {display: true, text: 'job #'},
              afterBuildTicks: axis => {
                axis.ticks = labels.map((l, i) => ({value: i + 1})).filter(t => t.value >= axis.min && t.value <= axis.max);
              },
              ticks: {autoSkip: true, maxRotation: 0, callback: v => String(v)}},
          y: {type: 'linear', beginAtZero: false, grace: '8%',
              ...boundedAxis(b, Math.min(...drawn), Math.max(...drawn))},
        },
      }),
    };
    config.options.plugins.dragZoom = {mode: 'x'};
    config.options.plugins.tooltip.callbacks = {
      title: items => items.length ? labels[Math.round(items[0].parsed.x) - 1] : '',
      label: item => `${item.dataset.label}: ${fmt(item.parsed.y)}` +
                     (item.raw.ci95 === null || item.raw.ci95 === undefined ? ' (one seed: no interval)' : ` ± ${fmt(item.raw.ci95)}`) +
                     (item.raw.text ? ' ' + item.raw.text : ''),
    };
    return canvasFor(config, width, height, 'jobseries');
  }

  // ------------------------------------------------------------ paths from above

  // paths: [{name, x: [], y: [], t: [], color, dash}] in metres, on equal scales; start and end marked.
  function paths({title, paths: list, width = 440, height = 470}) {
    const xs = list.flatMap(p => p.x), ys = list.flatMap(p => p.y);
    const lo = v => Math.min(...v), hi = v => Math.max(...v);
    const datasets = list.map((p, i) => ({
      type: 'scatter', label: p.name, role: 'path', showLine: true, borderColor: p.color || color(i), borderDash: p.dash || [],
      backgroundColor: p.color || color(i), borderWidth: 2, pointRadius: p.x.map((_, k) => (k === 0 || k === p.x.length - 1 ? 4 : 0)),
      pointStyle: p.x.map((_, k) => (k === 0 ? 'circle' : 'rectRot')),
      data: p.x.map((x, k) => ({x, y: p.y[k], t: p.t ? p.t[k] : undefined})),
    }));
    const config = {
      type: 'scatter',
      data: {datasets},
      options: baseOptions(title, {
        interaction: {mode: 'nearest', intersect: false},
        scales: {x: {type: 'linear', title: {display: true, text: 'x (m)'}, ticks: {includeBounds: false}},
                 y: {type: 'linear', title: {display: true, text: 'y (m)'}, ticks: {includeBounds: false}}},
      }),
    };
    config.options.plugins.dragZoom = {mode: 'xy'};
    config.options.plugins.tooltip.callbacks = {
      label: item => `${item.dataset.label}: (${fmt(item.parsed.x)}, ${fmt(item.parsed.y)}) m` +
                     (item.raw.t === undefined ? '' : ` at ${fmt(item.raw.t)} s`),
    };
    // Equal scale on both axes (the same metres per pixel), centred on the paths: set from the
    // plot area once it is laid out, twice, as the new ticks can move the area by a pixel or two.
    config.afterMount = chart => {
      if (!xs.length) return;
      const span = Math.max(hi(xs) - lo(xs), hi(ys) - lo(ys), 1) * 1.08;
      const mx = (hi(xs) + lo(xs)) / 2, my = (hi(ys) + lo(ys)) / 2;
      for (let pass = 0; pass < 2; pass++) {
        const a = chart.chartArea, o = chart.options.scales, perPx = span / Math.min(a.width, a.height);
        [o.x.min, o.x.max] = [mx - perPx * a.width / 2, mx + perPx * a.width / 2];
        [o.y.min, o.y.max] = [my - perPx * a.height / 2, my + perPx * a.height / 2];
        chart.update('none');
      }
    };
    return canvasFor(config, width, height, 'paths');
  }

  return {timeSeries, spread, jobSeries, paths, mount, destroyAll, fmt};
})();
