// findmug-web's Retrain page: run findmug-train / findmug-eval on chosen data folders
// (retrain.hpp on the server), follow the output, show the report's figures and the
// confusion, and Install the trained model: findmugd reloads it and its status says how.
'use strict';

const el = (id) => document.getElementById(id);
let offset = 0;
let lastJob = 0;
let shownReport = null;

async function api(method, path, body) {
  const res = await fetch(path, {
    method, cache: 'no-store',
    headers: body ? { 'Content-Type': 'application/json' } : {},
    body: body ? JSON.stringify(body) : undefined,
  });
  const answer = await res.json();
  if (!res.ok) throw new Error(answer.error || 'HTTP ' + res.status);
  return answer;
}

async function loadFolders() {
  const data = await api('GET', '/api/data');
  const list = el('folders');
  for (const f of data.folders) {
    const li = document.createElement('li');
    li.innerHTML = '<label><input type="checkbox"> <span></span></label>';
    li.querySelector('input').value = f.root;
    li.querySelector('input').dataset.root = f.root;
    li.querySelector('span').textContent = `${f.name} (${f.path})`;
    list.appendChild(li);
  }
}

function chosen() {
  return [...document.querySelectorAll('#folders input:checked')].map((i) => ({ root: Number(i.dataset.root), path: '' }));
}

function sets() {
  return el('sets').value.split('\n').map((s) => s.trim()).filter((s) => s.length > 0);
}

async function start(tool) {
  try {
    el('install-result').textContent = '';
    await api('POST', '/api/retrain/start', { tool, folders: chosen(), set: sets() });
    el('output').textContent = '';
    offset = 0;
  } catch (e) {
    el('install-result').textContent = 'not started: ' + e.message;
  }
}

function percent(x) {
  return typeof x === 'number' ? (100 * x).toFixed(1) + ' %' : '–';
}

function drawReport(report) {
  const body = el('figures').tBodies[0];
  body.textContent = '';
  for (const [name, key] of [['forest', 'forest'], ['forest + MRF', 'mrf'], ['patch oracle', 'oracle']]) {
    if (!report[key]) continue;
    const tr = body.insertRow();
    for (const v of [name, percent(report[key].global), percent(report[key].class_average)]) tr.insertCell().textContent = v;
  }
  const conf = el('confusion').tBodies[0];
  conf.textContent = '';
  const head = conf.insertRow();
  head.insertCell();
  for (const l of [...report.labels, 'void']) head.insertCell().textContent = l;
  report.mrf.confusion.forEach((row, t) => {
    const tr = conf.insertRow();
    tr.insertCell().textContent = report.labels[t];
    for (const n of row) tr.insertCell().textContent = n;
  });
}

async function poll() {
  try {
    const job = await api('GET', '/api/retrain/job?offset=' + offset);
    if (job.job !== lastJob) {
      el('output').textContent = '';
      lastJob = job.job;
    }
    if (job.output) {
      el('output').textContent += job.output;
      el('output').scrollTop = el('output').scrollHeight;
    }
    offset = job.next_offset;
    el('job-state').textContent = job.tool ? `${job.tool} ${job.state}` : job.state;
    el('job-state').className = 'badge ' + (job.state === 'running' ? 'stale' : job.state === 'succeeded' ? 'live' : job.state === 'idle' ? '' : 'down');
    el('install').disabled = !job.can_install || job.state === 'running';
    if (job.report && shownReport !== job.job) {
      drawReport(job.report);
      shownReport = job.job;
    }
    window.findmugRetrain = { state: job.state, tool: job.tool, report: job.report, model: job.model };
  } catch (e) {
    el('job-state').textContent = 'no connection: ' + e.message;
  }
  setTimeout(poll, 500);
}

async function install() {
  const out = el('install-result');
  try {
    const answer = await api('POST', '/api/retrain/install');
    out.textContent = `installed ${answer.installed}; findmugd asked to reload (request ${answer.request_id})…`;
    for (let i = 0; i < 150; ++i) {
      await new Promise((r) => setTimeout(r, 200));
      const live = await api('GET', '/api/live');
      const s = live.status;
      if (s && s.last_reload_request_id === answer.request_id) {
        out.textContent = s.last_reload_ok ? `findmugd runs the new model: ${s.last_reload_result}`
                                           : `findmugd refused it: ${s.last_reload_result}`;
        out.dataset.reload = s.last_reload_ok ? 'ok' : 'refused';
        return;
      }
    }
    out.textContent += ' no answer from findmugd yet (is it running, and listening for commands?)';
  } catch (e) {
    out.textContent = 'not installed: ' + e.message;
  }
}

el('train').addEventListener('click', () => start('train'));
el('eval').addEventListener('click', () => start('eval'));
el('cancel').addEventListener('click', () => api('POST', '/api/retrain/cancel').catch(() => {}));
el('install').addEventListener('click', install);
loadFolders().then(poll);
