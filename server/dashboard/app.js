// E-Navi Farm dashboard: one page, hash routes, reads the same JSON API as any script. This file
// holds what every page uses and the router; the pages are jobs.js, flights.js, compare.js and
// trend.js, the charts plots.js's (Chart.js). Everything a user or a job spec named (job names,
// labels, reasons, methods) is put into the page as text nodes, never as HTML, so a hostile name
// shows as the characters it is.
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

// ---------------------------------------------------------------- shared by the pages

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

// Once every page's script has run (they follow this one in index.html).
document.addEventListener('DOMContentLoaded', () => {
  window.addEventListener('hashchange', route);
  api('/api/info').then(i => {
    info = i;
    document.getElementById('build').textContent =
        `enavi ${i.enavi_version} (${i.git_commit})` + (i.read_only ? ', read-only' : '');
  }).catch(() => {}).finally(route);
});
