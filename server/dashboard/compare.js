// Two jobs compared (GET /api/compare): how they differ, the verdict, a board x scenario matrix
// and a cell's metrics and flights.
'use strict';

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
