// hairrig operator console. Plain ES module: no framework, no build step.
// The API it calls is the README's "Operator console" section.

const $ = (selector, root = document) => root.querySelector(selector);
const $$ = (selector, root = document) => [...root.querySelectorAll(selector)];

const KEY = { token: 'hairrig.token', client: 'hairrig.client', lease: 'hairrig.lease' };
const HEARTBEAT_MS = 5000;
const MESSAGE_MS = 6000;

const token = readToken();
const client = clientName();
const state = {
  lease: sessionStorage.getItem(KEY.lease),
  holder: null,
  busy: 'idle',
  estop: false,
  captureId: null,
  heartbeat: null,
  // Captures whose capture_end has arrived: a state or progress event that
  // left before the end (the e-stop's, say) cannot show them running again.
  ended: new Set(),
};

// ---------- small helpers ----------

function readToken() {
  const params = new URLSearchParams(location.search);
  if (params.has('token')) {
    sessionStorage.setItem(KEY.token, params.get('token'));
    params.delete('token'); // keep it out of the address bar and history
    const query = params.toString();
    history.replaceState(null, '', location.pathname + (query ? `?${query}` : '') + location.hash);
  }
  return sessionStorage.getItem(KEY.token);
}

function clientName() {
  let name = sessionStorage.getItem(KEY.client);
  if (!name) {
    const hex = crypto.getRandomValues(new Uint16Array(1))[0].toString(16).padStart(4, '0');
    name = `browser-${hex}`;
    sessionStorage.setItem(KEY.client, name);
  }
  return name;
}

// Adds the token (if any) to a URL used by <img>, <a> or EventSource.
function withToken(url) {
  if (!token) return url;
  return `${url}${url.includes('?') ? '&' : '?'}token=${encodeURIComponent(token)}`;
}

const capturePath = (id, rest = '') => `/api/captures/${encodeURIComponent(id)}${rest}`;
const fileUrl = (id, file) => withToken(capturePath(id, `/files/${file}`));

// Creates an element: el('td', {className: 'x', dataset: {a: 1}, attrs: {role: 'img'}}, 'text', child).
function el(tag, props = {}, ...children) {
  const node = document.createElement(tag);
  const { dataset, attrs, ...rest } = props;
  Object.assign(node, rest);
  Object.assign(node.dataset, dataset || {});
  for (const [name, value] of Object.entries(attrs || {})) node.setAttribute(name, value);
  node.append(...children.filter((c) => c !== null && c !== undefined));
  return node;
}

// A link that opens in a new tab.
const link = (className, href, ...children) =>
  el('a', { className, href, target: '_blank', rel: 'noopener' }, ...children);

function setText(selector, text) {
  $(selector).textContent = text ?? '';
}

const pad2 = (n) => String(n).padStart(2, '0');
const fmtNumber = (x, digits) => (Number.isFinite(x) ? x.toFixed(digits) : '—');

function formatEta(seconds) {
  if (!Number.isFinite(seconds) || seconds < 0) return '';
  const s = Math.round(seconds);
  return s < 60 ? `ETA ${s} s` : `ETA ${Math.floor(s / 60)} min ${pad2(s % 60)} s`;
}

// ---------- messages ----------

let messageTimer = null;

function showMessage(text, kind = 'error') {
  const box = $('#message');
  box.textContent = text;
  box.dataset.kind = kind;
  box.hidden = false;
  clearTimeout(messageTimer);
  messageTimer = setTimeout(() => { box.hidden = true; }, MESSAGE_MS);
}

// ---------- API ----------

const apiError = (status, message, data) => Object.assign(new Error(message), { status, data });

// One request to the server; throws an Error (with status and data) carrying the server's {"error"} text.
async function api(method, path, body) {
  const headers = {};
  if (token) headers.Authorization = `Bearer ${token}`;
  if (method !== 'GET' && state.lease) headers['X-Hairrig-Lease'] = state.lease;
  if (method !== 'GET' && body === undefined) body = {};  // a change is always JSON (the server refuses others)
  if (body !== undefined) headers['Content-Type'] = 'application/json';
  let response;
  try {
    response = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  } catch (err) {
    throw apiError(0, `${method} ${path}: server unreachable`, {});
  }
  const data = await response.json().catch(() => ({}));
  if (response.status === 403) lostControl(data.holder);
  if (!response.ok) {
    throw apiError(response.status, data.error || `${method} ${path}: HTTP ${response.status}`, data);
  }
  return data;
}

// Runs a user action; any failure goes to the message area.
async function attempt(action) {
  try {
    return await action();
  } catch (err) {
    showMessage(err.message);
    return undefined;
  }
}

function onClick(selector, action) {
  $(selector).addEventListener('click', () => attempt(action));
}

// ---------- control ----------

const holdingControl = () => Boolean(state.lease) && state.holder === client;

const enableWhen = {
  idle: () => state.busy === 'idle' && !state.estop,
  // The devices are the console's again while a capture is calibrated or reconstructed.
  devices: () => state.busy !== 'capturing' && !state.estop,
  capturing: () => state.busy === 'capturing',
};

function renderControl() {
  const mine = holdingControl();
  setText('#control-status', mine ? 'You control the rig'
    : state.holder ? `Read-only: ${state.holder} holds control` : 'Nobody holds control');
  $('#control-status').dataset.mine = mine;
  document.body.classList.toggle('read-only', !mine);
  $('#take-control').disabled = mine;
  $('#release-control').disabled = !mine;
  for (const node of $$('[data-needs-control]')) {
    const condition = enableWhen[node.dataset.when];
    node.disabled = !mine || (condition ? !condition() : false);
  }
}

function setLease(lease, holder) {
  state.lease = lease;
  state.holder = holder;
  if (lease) sessionStorage.setItem(KEY.lease, lease);
  else sessionStorage.removeItem(KEY.lease);
  clearInterval(state.heartbeat);
  state.heartbeat = lease ? setInterval(heartbeat, HEARTBEAT_MS) : null;
  renderControl();
}

function lostControl(holder) {
  if (state.lease) setLease(null, holder ?? null);
}

async function heartbeat() {
  const reply = await attempt(() => api('POST', '/api/control/heartbeat'));
  if (reply && 'holder' in reply) {
    state.holder = reply.holder;
    renderControl();
  }
}

async function claimControl(take) {
  const reply = await api('POST', '/api/control', take ? { client, take: true } : { client });
  setLease(reply.lease, reply.holder);
}

async function takeControl() {
  try {
    await claimControl(false);
  } catch (err) {
    if (err.status !== 409) throw err;
    if (confirm(`Take control from ${err.data.holder}?`)) await claimControl(true);
  }
}

async function releaseControl() {
  await api('DELETE', '/api/control');
  setLease(null, null);
}

// ---------- header state ----------

function applyState(s) {
  setText('#rig-name', s.rig?.name);
  $('#rig-name').title = s.rig?.config ?? '';
  setText('#version', s.version ? `hairrig ${s.version}` : '');
  state.holder = s.control?.holder ?? null;
  state.busy = s.busy ?? 'idle';
  setText('#busy', state.busy);
  $('#busy').dataset.state = state.busy;
  applyEstop(s.estop);
  if (s.lights) applyLights(s.lights);
  if (s.turntable) applyAngle(s.turntable.angle_deg);
  if (s.capture) showCapture(s.capture);
  renderControl();
}

function applyEstop(estop = {}) {
  state.estop = Boolean(estop.active);
  $('#estop-banner').hidden = !state.estop;
  setText('#estop-reason', estop.reason);
  document.body.classList.toggle('estopped', state.estop);
  renderControl();
}

// POST /api/estop or /api/estop/release; both answer {"estop"}. The journal names the client.
const postEstop = (path) => async () => applyEstop((await api('POST', path, { client })).estop);

// ---------- devices ----------

function deviceRow(d) {
  const reconnect = rigButton('reconnect', 'Reconnect', 'devices', async () => {
    const row = await api('POST', `/api/devices/${encodeURIComponent(d.name)}/reconnect`);
    $(`#devices tr[data-device="${CSS.escape(d.name)}"]`).replaceWith(deviceRow(row));
    renderControl();
  });
  reconnect.title = `Close and reopen ${d.name}`;
  const cells = ['name', 'kind', 'backend', 'model', 'serial', 'state', 'health'].map((key) =>
    el('td', { className: key, textContent: d[key] ?? '', dataset: { value: d[key] ?? '' } }));
  return el('tr', { dataset: { device: d.name } }, ...cells, el('td', {}, reconnect));
}

async function loadDevices() {
  const { devices = [] } = await api('GET', '/api/devices');
  $('#devices tbody').replaceChildren(...devices.map(deviceRow));
  renderControl();
}

// ---------- live view ----------

const ms = (s) => (Number.isFinite(s) ? +(s * 1000).toFixed(3) : '');

function cameraCard(cam) {
  const apply = el('button', { type: 'button', className: 'apply', textContent: 'Apply',
    dataset: { needsControl: '' } });
  const card = el('article', { className: 'camera no-frame', dataset: { camera: cam.name } },
    el('h3', {}, cam.name, el('span', { className: 'serial', textContent: cam.serial ?? '' })),
    el('img', { className: 'preview', alt: `Live view of ${cam.name}`, width: 480, height: 320,
      onerror: () => card.classList.add('no-frame'), onload: () => card.classList.remove('no-frame') }),
    el('canvas', { className: 'histogram', width: 256, height: 48,
      attrs: { role: 'img', 'aria-label': `Luminance histogram of ${cam.name}` } }),
    el('div', { className: 'meta' },
      el('span', { className: 'fps', textContent: '— fps' }),
      el('span', { className: 'clipped', textContent: 'clipped', hidden: true }),
      el('span', { className: 'size', textContent: `${cam.width_px ?? '?'}×${cam.height_px ?? '?'}` })),
    el('div', { className: 'settings' },
      el('label', {}, 'Exposure (ms) ', el('input', { className: 'exposure', type: 'number', step: 'any' })),
      el('label', {}, 'Gain (dB) ', el('input', { className: 'gain', type: 'number', step: 0.1 })),
      apply));
  apply.addEventListener('click', () => attempt(() => applyCameraSettings(card)));
  fillCameraSettings(card, cam);
  return card;
}

function fillCameraSettings(card, cam) {
  const exposure = $('input.exposure', card);
  exposure.min = ms(cam.min_exposure_s);
  exposure.max = ms(cam.max_exposure_s);
  exposure.value = ms(cam.exposure_s);
  $('input.gain', card).value = cam.gain_db ?? '';
}

async function applyCameraSettings(card) {
  const body = {};
  const exposureMs = $('input.exposure', card).valueAsNumber;
  const gain = $('input.gain', card).valueAsNumber;
  if (isFinite(exposureMs)) body.exposure_s = exposureMs / 1000;
  if (isFinite(gain)) body.gain_db = gain;
  if (!Object.keys(body).length) throw new Error('Enter an exposure (ms) or a gain (dB) first');
  const name = card.dataset.camera;
  fillCameraSettings(card, await api('POST', `/api/cameras/${encodeURIComponent(name)}/settings`, body));
  showMessage(`${name}: settings applied`, 'info');
}

async function loadCameras() {
  const { cameras = [] } = await api('GET', '/api/cameras');
  $('#live').replaceChildren(...cameras.map(cameraCard));
  for (const cam of cameras) if (cam.live) applyPreview({ camera: cam.name, ...cam.live });
  renderControl();
}

function applyPreview(p) {
  const card = $(`#live .camera[data-camera="${CSS.escape(p.camera)}"]`);
  if (!card) return;
  if (p.seq !== undefined && p.seq !== null) {
    const url = `/api/cameras/${encodeURIComponent(p.camera)}/preview.jpg?seq=${encodeURIComponent(p.seq)}`;
    $('img.preview', card).src = withToken(url);
  }
  $('.fps', card).textContent = `${fmtNumber(p.fps, 1)} fps`;
  const clipped = $('.clipped', card);
  clipped.hidden = !(p.clipped_fraction > 0.01);
  clipped.textContent = `clipped ${(100 * (p.clipped_fraction || 0)).toFixed(1)} %`;
  if (Array.isArray(p.histogram)) drawHistogram($('canvas.histogram', card), p.histogram);
}

// 64 luminance bins, scaled to the tallest; the last bin (clipping) in red.
function drawHistogram(canvas, bins) {
  const ctx = canvas.getContext('2d');
  const { width, height } = canvas;
  const top = Math.max(1, ...bins);
  const w = width / bins.length;
  ctx.clearRect(0, 0, width, height);
  bins.forEach((count, i) => {
    const h = Math.max(count > 0 ? 1 : 0, (count / top) * height);
    ctx.fillStyle = i === bins.length - 1 && count > 0 ? '#c62828' : '#37474f';
    ctx.fillRect(i * w, height - h, Math.max(1, w - 1), h);
  });
}

// ---------- lights and turntable ----------

// Sides whose switch the operator has just changed: the state the server
// reports for them is not shown until their own request has answered, so an
// answer or event that left before the change cannot undo the click.
const lightsInFlight = new Set();

function applyLights(lights) {
  for (const side of ['top', 'bottom']) {
    if (side in lights && !lightsInFlight.has(side)) {
      $(`#light-${side}`).checked = Boolean(lights[side]);
    }
  }
}

async function setLight(side, on) {
  lightsInFlight.add(side);
  try {
    const lights = (await api('POST', '/api/lights', { [side]: on })).lights ?? {};
    $(`#light-${side}`).checked = Boolean(lights[side] ?? on);
  } catch (err) {
    $(`#light-${side}`).checked = !on;
    throw err;
  } finally {
    lightsInFlight.delete(side);
  }
}

function applyAngle(deg) {
  setText('#turntable-angle', Number.isFinite(deg) ? `${deg.toFixed(1)}°` : 'not homed');
}

async function jog(sign) {
  const step = $('#jog-step').valueAsNumber;
  if (!(step > 0 && step <= 360)) throw new Error('Jog step must be between 0 and 360 degrees');
  applyAngle((await api('POST', '/api/turntable/jog', { degrees: sign * step })).angle_deg);
}

// ---------- capture ----------

async function loadPlan() {
  const plan = await api('GET', '/api/plan');
  const bound = plan.expected_s < 10 ? plan.expected_s.toFixed(1) : Math.round(plan.expected_s);
  setText('#plan-summary', `${plan.views} views, ${plan.stops} stops, at least ${bound} s`);
  $('#plan-summary').title = `cameras: ${(plan.cameras || []).join(', ')}; exposure ${fmtNumber(
    plan.exposure_s * 1000, 2)} ms, gain ${fmtNumber(plan.gain_db, 1)} dB`;
}

// Switches the capture panel to another capture (clears thumbnails and faults).
function selectCapture(id) {
  if (!id || id === state.captureId) return false;
  state.captureId = id;
  $('#thumbnails').replaceChildren();
  $('#faults').replaceChildren();
  setText('#capture-id', id);
  setText('#fault-count', '0');
  setText('#capture-message', '');
  return true;
}

function showCapture(c, ending = false) {
  if (ending) state.ended.add(c.id);
  else if (state.ended.has(c.id)) return;
  if (selectCapture(c.id)) attempt(() => loadCaptureViews(c.id));
  setText('#capture-status', c.status);
  $('#capture-status').dataset.status = c.status ?? '';
  const done = c.views_done ?? 0;
  const total = c.views_total ?? 0;
  $('#progress').max = Math.max(1, total);
  $('#progress').value = done;
  setText('#progress-text', `${done} / ${total} views`);
  setText('#eta', c.status === 'running' ? formatEta(c.eta_s) : '');
  // `stop` counts from 0, as the capture plan does.
  setText('#current-stop', c.status === 'running' && Number.isInteger(c.stop) && c.stops_total
    ? `stop ${c.stop + 1} of ${c.stops_total}` : '');
  setText('#step', c.step);
  if (c.message) setText('#capture-message', c.message);
  if (typeof c.faults === 'number') setText('#fault-count', c.faults);
}

function addThumb(v) {
  if ($(`#thumbnails img.thumb[data-view="${CSS.escape(String(v.view))}"]`)) return;
  const label = `view ${v.view}${v.camera ? ` (${v.camera})` : ''}`;
  const src = v.thumb ?? capturePath(v.id ?? state.captureId, `/views/${v.view}/thumb.jpg`);
  $('#thumbnails').append(el('img', { className: 'thumb', src: withToken(src), alt: label, title: label,
    dataset: { view: v.view } }));
}

async function loadCaptureViews(id) {
  const capture = await api('GET', capturePath(id));
  if (id === state.captureId) (capture.views || []).forEach(addThumb);
}

function addFault(f) {
  selectCapture(f.id);
  $('#faults').append(el('li', { textContent: f.what }));
  if (typeof f.faults === 'number') setText('#fault-count', f.faults);
}

async function startCapture() {
  const subject = $('#subject').value.trim();
  if (!subject) throw new Error('Enter a subject first');
  const reply = await api('POST', '/api/captures',
    { subject, calibrate: $('#calibrate').checked, reconstruct: $('#reconstruct').checked });
  watchCapture(reply.id, 'started', false);
}

// Shows a capture the page just started, resumed or replayed.
function watchCapture(id, word, hasViews) {
  state.ended.delete(id);
  if (selectCapture(id) && hasViews) attempt(() => loadCaptureViews(id));
  setText('#capture-status', word);
  showMessage(`Capture ${id} ${word}`, 'info');
}

async function stopCapture() {
  await api('POST', '/api/capture/stop');
  setText('#capture-message', 'stopping after the current stop…');
}

// ---------- result ----------

async function openResult(id) {
  showResult(await api('GET', capturePath(id)));
}

function showResult(capture) {
  const cal = capture.calibration;
  setText('#result-id', `${capture.id}${capture.subject ? ` · ${capture.subject}` : ''}`);
  setText('#verdict', cal ? cal.verdict : 'not calibrated');
  $('#verdict').dataset.verdict = cal?.verdict ?? '';
  setText('#rms-total', Number.isFinite(cal?.rms_px) ? `RMS ${cal.rms_px.toFixed(3)} px` : '');
  drawRmsPlot($('#rms-plot'), cal?.views ?? []);
  fillImages('#residuals', cal?.residuals ?? [], 'residuals');
  const rec = capture.reconstruction;
  setText('#reconstruction-verdict', rec ? rec.verdict : 'not reconstructed');
  $('#reconstruction-verdict').dataset.verdict = rec?.verdict ?? '';
  $('#reconstruction-reasons').replaceChildren(
    ...(rec?.reasons ?? []).map((reason) => el('li', { textContent: reason })));
  showFigures(capture.reconstruction_figures);
  attempt(() => showModel(capture.files?.model ?? null));
  fillImages('#reconstruction', capture.files?.reconstruction ?? [], 'reconstruction preview');
  const downloads = (capture.files?.downloads ?? []).map((url) => {
    const name = url.split('/files/').pop();
    const a = link('', withToken(url), name);
    a.download = name.split('/').pop();
    return el('li', {}, a);
  });
  $('#downloads').replaceChildren(
    ...(downloads.length ? downloads : [el('li', { className: 'none', textContent: 'none' })]));
}

function showFigures(f) {
  const rows = [
    ['oriented points', f?.points, (x) => x.toLocaleString('en')],
    ['directions agree where depths agree', f?.direction_agreement, (x) => `${(100 * x).toFixed(1)} %`],
    ['strands', f?.strands, (x) => x.toLocaleString('en')],
    ['mean strand length', f?.strand_mean_length_mm, (x) => `${x.toFixed(0)} mm`],
  ].filter(([, value]) => Number.isFinite(value));
  $('#reconstruction-figures').replaceChildren(...rows.map(([name, value, format]) =>
    el('div', {}, el('dt', { textContent: name }), el('dd', { textContent: format(value) }))));
}

// ---------- 3D view (viewer.js, loaded with three.js when a capture has a model) ----------

// `generation` counts the models asked for: a load that finishes after a
// newer one was asked for is dropped.
const view3d = { viewer: null, url: null, generation: 0, creating: null };

async function showModel(url) {
  $('#viewer').hidden = !url;
  if (!url) {
    view3d.viewer?.clear();
    view3d.url = null;
    return;
  }
  if (url === view3d.url) return;
  view3d.url = url;
  const generation = ++view3d.generation;
  setText('#viewer-status', 'loading…');
  let holds;
  try {
    if (!view3d.viewer) {
      view3d.creating ??= import('./viewer.js').then(({ HairViewer }) => new HairViewer($('#viewer-canvas')));
      view3d.viewer = await view3d.creating;
      window.hairrigViewer = view3d.viewer;  // for the browser test and bench/console_viewer_bench
    }
    if (generation !== view3d.generation) return;
    holds = await view3d.viewer.load(withToken(url));
    if (!holds) return;  // a newer model was asked for
  } catch (err) {
    if (generation === view3d.generation) {
      setText('#viewer-status', err.message);
      view3d.url = null;
    }
    view3d.creating = null;
    throw err;
  }
  if (generation !== view3d.generation) return;
  for (const part of ['strands', 'points', 'head', 'truth']) {
    const box = $(`#show-${part}`);
    box.disabled = !holds[part];
    box.checked = holds[part] && (part === 'strands' || part === 'head');
    box.parentElement.title = holds[part] ? '' : `this capture's model has no ${part}`;
  }
  const byWisp = $('#colour-by option[value="wisp"]');
  byWisp.disabled = !holds.wisps;
  byWisp.title = holds.wisps ? '' : 'no fitted model names the wisps (hairrig fit, then hairrig export)';
  if (!holds.wisps && $('#colour-by').value === 'wisp') $('#colour-by').value = 'direction';
  $('#play-simulation').disabled = !holds.animation;
  $('#play-simulation').textContent = 'Play simulation';
  if ($('#colour-by').value !== view3d.viewer.colourMode) view3d.viewer.setColourBy($('#colour-by').value);
  setText('#viewer-status', holds.animation
    ? `simulation "${holds.animation}", ${holds.duration.toFixed(1)} s` : 'no simulation in this model');
}

function wireViewer() {
  for (const part of ['strands', 'points', 'head', 'truth']) {
    $(`#show-${part}`).addEventListener('change', (e) => view3d.viewer?.setVisible(part, e.target.checked));
  }
  $('#colour-by').addEventListener('change', (e) => view3d.viewer?.setColourBy(e.target.value));
  onClick('#play-simulation', () => {
    const viewer = view3d.viewer;
    if (!viewer) return;
    if (viewer.playing) viewer.pause(); else viewer.play();
    $('#play-simulation').textContent = viewer.playing ? 'Stop simulation' : 'Play simulation';
  });
}

function fillImages(selector, urls, what) {
  const links = urls.map((url) => link('', withToken(url),
    el('img', { src: withToken(url), alt: `${what}: ${url.split('/').pop()}`, loading: 'lazy' })));
  $(selector).replaceChildren(...(links.length ? links : [el('span', { className: 'none', textContent: 'none' })]));
}

// Bars of RMS (px) per view; unsolved views as red crosses at the base.
function drawRmsPlot(canvas, views) {
  const ctx = canvas.getContext('2d');
  const { width, height } = canvas;
  const left = 40, bottom = 18, top = 8;
  const plotH = height - bottom - top;
  ctx.clearRect(0, 0, width, height);
  ctx.font = '11px system-ui, sans-serif';
  ctx.fillStyle = '#607d8b';
  if (!views.length) {
    ctx.fillText('no per-view calibration', left, height / 2);
    return;
  }
  const maxRms = Math.max(0.1, ...views.map((v) => v.rms_px || 0)) * 1.1;
  const y = (rms) => top + plotH - (rms / maxRms) * plotH;
  ctx.strokeStyle = '#cfd8dc';
  for (const tick of [0, maxRms / 2, maxRms]) {
    ctx.beginPath(); ctx.moveTo(left, y(tick)); ctx.lineTo(width, y(tick)); ctx.stroke();
    ctx.fillText(tick.toFixed(2), 2, y(tick) + 4);
  }
  const w = (width - left) / views.length;
  const labelEvery = Math.max(1, Math.ceil(views.length / Math.floor((width - left) / 40)));
  views.forEach((v, i) => {
    const x = left + i * w;
    if (v.solved === false || !Number.isFinite(v.rms_px)) {
      ctx.fillStyle = '#c62828';
      ctx.fillText('×', x + w / 2 - 3, top + plotH - 2);
    } else {
      ctx.fillStyle = '#1565c0';
      ctx.fillRect(x + 1, y(v.rms_px), Math.max(1, w - 2), top + plotH - y(v.rms_px));
    }
    if (i % labelEvery === 0) {
      ctx.fillStyle = '#607d8b';
      ctx.fillText(String(v.name ?? i).split('/').pop().split('_')[0], x, height - 4);  // the view number
    }
  });
}

// ---------- archive ----------

function actionButton(className, text, action) {
  const button = el('button', { type: 'button', className, textContent: text });
  button.addEventListener('click', () => attempt(action));
  return button;
}

// A button that changes the rig: needs control and the rig in state `when` (enableWhen).
function rigButton(className, text, when, action) {
  const button = actionButton(className, text, action);
  Object.assign(button.dataset, { needsControl: '', when });
  return button;
}

function archiveRow(c) {
  const resumable = c.status === 'incomplete' || c.status === 'stopped';
  const cal = c.calibration;
  const actions = el('td', { className: 'actions' },
    resumable ? rigButton('resume', 'Resume', 'idle', async () => {
      watchCapture((await api('POST', capturePath(c.id, '/resume'))).id, 'resumed', true);
    }) : null,
    rigButton('replay', 'Replay', 'idle', async () => {
      watchCapture((await api('POST', capturePath(c.id, '/replay'))).id, 'replaying', false);
    }),
    actionButton('open', 'Open', async () => {
      await openResult(c.id);
      $('#result').scrollIntoView({ behavior: 'smooth', block: 'start' });
    }),
    link('contact-sheet', fileUrl(c.id, 'contact_sheet.png'), 'contact sheet'),
    link('journal', fileUrl(c.id, 'journal.jsonl'), 'journal'));
  return el('tr', { dataset: { capture: c.id } },
    el('td', { className: 'id', textContent: c.id }),
    el('td', { textContent: c.subject ?? '' }),
    el('td', { className: 'numbers', textContent: c.started ?? '' }),
    el('td', { className: 'status', textContent: c.status, dataset: { status: c.status } }),
    el('td', { className: 'views numbers', textContent: `${c.views_completed} / ${c.views_planned}` }),
    el('td', { className: 'verdict', dataset: { verdict: cal?.verdict ?? '' },
      textContent: cal ? `${cal.verdict} (${fmtNumber(cal.rms_px, 2)} px)` : '—' }),
    actions);
}

async function loadArchive() {
  const { captures = [] } = await api('GET', '/api/captures');
  $('#archive tbody').replaceChildren(...captures.map(archiveRow));
  renderControl();
}

// ---------- event stream ----------

const handlers = {
  state: (s) => { applyState(s); attempt(loadDevices); },
  progress: showCapture,
  view: (v) => { selectCapture(v.id); addThumb(v); },
  fault: addFault,
  capture_end: (c) => { showCapture(c, true); attempt(loadArchive); },
  processed: (p) => { attempt(() => openResult(p.id)); attempt(loadArchive); },
  preview: applyPreview,
};

function connectEvents() {
  const source = new EventSource(withToken('/api/events'));
  const connection = $('#connection');
  source.onopen = () => {
    connection.textContent = 'live';
    connection.dataset.state = 'up';
    if (state.captureId) attempt(() => loadCaptureViews(state.captureId)); // fill views missed while away
  };
  source.onerror = () => {
    connection.textContent = 'reconnecting';
    connection.dataset.state = 'down';
    // EventSource gives up on some failures (e.g. 401, 5xx): start a new one then.
    if (source.readyState === EventSource.CLOSED) setTimeout(connectEvents, 3000);
  };
  for (const [name, handle] of Object.entries(handlers)) {
    source.addEventListener(name, (event) => {
      let data;
      try { data = JSON.parse(event.data); } catch { return; }
      handle(data);
    });
  }
}

// ---------- start ----------

function wire() {
  onClick('#take-control', takeControl);
  onClick('#release-control', releaseControl);
  onClick('#estop', postEstop('/api/estop'));
  onClick('#estop-release', postEstop('/api/estop/release'));
  onClick('#jog-minus', () => jog(-1));
  onClick('#jog-plus', () => jog(1));
  onClick('#home', async () => applyAngle((await api('POST', '/api/turntable/home')).angle_deg));
  onClick('#stop-capture', stopCapture);
  for (const side of ['top', 'bottom']) {
    $(`#light-${side}`).addEventListener('change', (e) => attempt(() => setLight(side, e.target.checked)));
  }
  $('#capture-form').addEventListener('submit', (e) => {
    e.preventDefault();
    attempt(startCapture);
  });
  wireViewer();
}

async function start() {
  setText('#client-name', `client ${client}`);
  wire();
  renderControl();
  connectEvents();
  [loadDevices, loadCameras, loadPlan, loadArchive].forEach(attempt);
  const initial = await attempt(() => api('GET', '/api/state'));
  if (initial) applyState(initial);
  if (initial?.capture && initial.capture.status !== 'running') attempt(() => openResult(initial.capture.id));
  // After a reload: keep a lease the server still gives us, drop a stale one.
  if (state.lease) setLease(state.holder === client ? state.lease : null, state.holder);
}

start();
