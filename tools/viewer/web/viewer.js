// whiskeye-viewer's page: plain JavaScript, Canvas, no library. Live: the whole state from
// /api/snapshot, then what changed by Server-Sent Events (/api/events). A log: /api/snapshot?t= for
// the slider's time. The JSON's sections are described in docs/viewer.md.
'use strict';

const S = { v: -1 };        // the state as last received, by section
let mode = null;            // 'live' or 'log'
let log = null;             // {start, end} of a log
let sliderT = null;         // the log time shown
const $ = (id) => document.getElementById(id);

function fmt(v, digits) {
  return v === null || v === undefined || Number.isNaN(v) ? '—' : Number(v).toFixed(digits);
}

function timeText(utime) {
  if (!utime) return '—';
  const d = new Date(utime / 1000);
  return d.toISOString().replace('T', ' ').replace('Z', '').slice(0, 21);
}

// ---- the experience map, the trail and the pose ----
function drawMap() {
  const c = $('map');
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const map = S.map, trail = S.trail, pose = S.pose;
  let xs = [], ys = [];
  if (map) { xs = xs.concat(map.x); ys = ys.concat(map.y); }
  if (trail) for (let i = 0; i < trail.xy.length; i += 2) { xs.push(trail.xy[i]); ys.push(trail.xy[i + 1]); }
  if (pose) { xs.push(pose.x); ys.push(pose.y); }
  if (xs.length === 0) {
    g.fillStyle = '#8a94a6'; g.font = '14px system-ui'; g.textAlign = 'center';
    g.fillText('no map yet (VITA_MAP, VITA_POSE)', c.width / 2, c.height / 2);
    return;
  }
  let x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
  const pad = 0.5;
  x0 -= pad; x1 += pad; y0 -= pad; y1 += pad;
  const k = Math.min(c.width / (x1 - x0), c.height / (y1 - y0));
  const ox = (c.width - k * (x1 - x0)) / 2, oy = (c.height - k * (y1 - y0)) / 2;
  const X = (x) => ox + k * (x - x0), Y = (y) => c.height - (oy + k * (y - y0));
  // A 1 m grid, with the axes through the map's origin.
  g.lineWidth = 1;
  for (let gx = Math.ceil(x0); gx <= x1; gx++) {
    g.strokeStyle = gx === 0 ? '#3b4452' : '#232a33';
    g.beginPath(); g.moveTo(X(gx), 0); g.lineTo(X(gx), c.height); g.stroke();
  }
  for (let gy = Math.ceil(y0); gy <= y1; gy++) {
    g.strokeStyle = gy === 0 ? '#3b4452' : '#232a33';
    g.beginPath(); g.moveTo(0, Y(gy)); g.lineTo(c.width, Y(gy)); g.stroke();
  }
  g.fillStyle = '#6e7681'; g.font = '11px system-ui'; g.textAlign = 'left';
  g.fillText('1 m grid', 6, c.height - 6);
  if (map) {
    const at = new Map();
    map.id.forEach((id, i) => at.set(id, i));
    // Links in grey; those the back end revoked (the rest of the map disagrees) dashed in pink.
    for (const revoked of [0, 1]) {
      g.strokeStyle = revoked ? '#f778ba' : '#4b5563'; g.lineWidth = 1;
      g.setLineDash(revoked ? [4, 3] : []);
      g.beginPath();
      for (let i = 0; i + 1 < map.links.length; i += 2) {
        if ((map.revoked[i / 2] || 0) !== revoked) continue;
        const a = at.get(map.links[i]), b = at.get(map.links[i + 1]);
        if (a === undefined || b === undefined) continue;
        g.moveTo(X(map.x[a]), Y(map.y[a])); g.lineTo(X(map.x[b]), Y(map.y[b]));
      }
      g.stroke();
    }
    g.setLineDash([]);
  }
  // The trail over the links (where the robot went, in the map frame), under the experiences.
  if (trail && trail.xy.length >= 4) {
    g.strokeStyle = 'rgba(63,185,80,0.85)'; g.lineWidth = 2;
    g.beginPath(); g.moveTo(X(trail.xy[0]), Y(trail.xy[1]));
    for (let i = 2; i < trail.xy.length; i += 2) g.lineTo(X(trail.xy[i]), Y(trail.xy[i + 1]));
    g.stroke();
  }
  if (map) {
    const at = new Map();
    map.id.forEach((id, i) => at.set(id, i));
    const r = Math.max(2.5, Math.min(5, k * 0.04));
    map.id.forEach((id, i) => {
      g.fillStyle = map.dense[i] ? '#58a6ff' : '#a371f7';
      g.beginPath(); g.arc(X(map.x[i]), Y(map.y[i]), r, 0, 2 * Math.PI); g.fill();
    });
    const cur = at.get(map.current);
    if (cur !== undefined) {
      g.strokeStyle = '#f0883e'; g.lineWidth = 3;
      g.beginPath(); g.arc(X(map.x[cur]), Y(map.y[cur]), r + 5, 0, 2 * Math.PI); g.stroke();
    }
  }
  if (pose) {
    const px = X(pose.x), py = Y(pose.y), t = pose.theta, s = 12;
    g.fillStyle = '#ffffff'; g.strokeStyle = '#0d1117'; g.lineWidth = 1.5;
    g.beginPath();
    g.moveTo(px + s * Math.cos(t), py - s * Math.sin(t));
    g.lineTo(px + 0.6 * s * Math.cos(t + 2.5), py - 0.6 * s * Math.sin(t + 2.5));
    g.lineTo(px + 0.6 * s * Math.cos(t - 2.5), py - 0.6 * s * Math.sin(t - 2.5));
    g.closePath(); g.fill(); g.stroke();
  }
}

function renderMap() {
  const m = S.map;
  $('num-experiences').textContent = m ? m.num_experiences : 0;
  $('num-dense').textContent = m ? m.num_dense : 0;
  $('num-sparse').textContent = m ? m.num_sparse : 0;
  $('num-links').textContent = m ? m.num_links : 0;
  $('num-revoked').textContent = m ? m.num_revoked : 0;
  $('current-experience').textContent = m && m.current >= 0 ? m.current : '—';
  $('map-mode').textContent = m ? m.mode + ' mode' : '';
  const p = S.pose;
  $('pose').textContent = p
    ? `pose x ${fmt(p.x, 2)} m, y ${fmt(p.y, 2)} m, θ ${fmt(p.theta * 180 / Math.PI, 0)}°, experience ${p.experience_id}, template ${p.template_id}`
    : 'pose —';
  // LOCALISING: slamd does not know where it is (after a suspected kidnap, or on a saved map); the
  // pose above claims nothing until it commits.
  const loc = $('localisation');
  loc.textContent = !p ? '—' : p.localising ? 'LOCALISING' : 'tracking';
  loc.className = p && p.localising ? 'state localising' : 'state';
  drawMap();
}

// ---- the camera ----
function renderCamera() {
  const c = S.camera;
  if (!c) { $('camera-info').textContent = 'no frame yet'; return; }
  $('camera-info').textContent = `${c.width}×${c.height}, frame ${c.frame}`;
  const url = mode === 'log' ? `/api/camera.jpg?t=${sliderT}` : `/api/camera.jpg?frame=${c.frame}`;
  const img = $('camera');
  if (img.getAttribute('src') !== url) img.setAttribute('src', url);
}

// ---- the whisker array: two sides of 4 rows × 3 columns, front column first ----
function drawWhiskers() {
  const c = $('whiskers');
  const g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const w = S.whiskers;
  if (!w) {
    $('whisker-info').textContent = 'no whisk cycle yet';
    g.fillStyle = '#8a94a6'; g.font = '13px system-ui'; g.textAlign = 'center';
    g.fillText('no WHISK_CYCLE yet', c.width / 2, c.height / 2);
    return;
  }
  $('whisker-info').textContent = `cycle ${w.cycle}: ${w.num_contacts} of ${w.contact.length} touching` +
    (w.num_missing ? `, ${w.num_missing} samples lost` : '');
  const rows = w.rows, cols = w.columns, half = cols / 2;
  const cell = 34, top = 34;
  const sides = [{ name: 'left', x: 20, first: 0 }, { name: 'right', x: c.width / 2 + 10, first: half }];
  g.font = '11px system-ui'; g.textAlign = 'center';
  for (const side of sides) {
    g.fillStyle = '#8a94a6';
    g.fillText(`${side.name} (front → back)`, side.x + cell * half / 2 + 12, 16);
    for (let r = 0; r < rows; r++) {
      for (let k = 0; k < half; k++) {
        const col = side.first + k, i = r * cols + col;
        const cx = side.x + 18 + k * (cell + 8), cy = top + r * (cell + 4) + 4;
        const d = w.deflection[i];
        if (d === null) {  // not measured this cycle (a dead whisker, a board offline)
          g.strokeStyle = '#6e7681'; g.lineWidth = 1.5;
          g.beginPath(); g.moveTo(cx - 8, cy - 8); g.lineTo(cx + 8, cy + 8); g.moveTo(cx + 8, cy - 8); g.lineTo(cx - 8, cy + 8); g.stroke();
          continue;
        }
        const a = Math.min(1, d);
        g.fillStyle = `rgba(88,166,255,${0.15 + 0.85 * a})`;
        g.beginPath(); g.arc(cx, cy, 12, 0, 2 * Math.PI); g.fill();
        if (w.contact[i]) {
          g.strokeStyle = '#f85149'; g.lineWidth = 3;
          g.beginPath(); g.arc(cx, cy, 15, 0, 2 * Math.PI); g.stroke();
        }
      }
    }
  }
  g.textAlign = 'left'; g.fillStyle = '#8a94a6';
  g.fillText('fill: peak deflection · red ring: contact · ×: not measured', 10, c.height - 6);
}

// ---- the last event and template match ----
function renderEvent() {
  const e = S.event, box = $('event');
  if (!e || !e.last) {
    box.className = 'event none';
  } else {
    const l = e.last;
    box.className = 'event ' + l.type;
    const names = { new: 'new experience', relocalise: 're-localised', same: 'same experience' };
    $('event-type').textContent = names[l.type] || l.type;
    $('event-detail').textContent = `cycle ${l.cycle}: ${l.from_id} → ${l.to_id}, template ${l.template_id}`;
  }
  if (e) $('event-counts').textContent = `${e.counts.new} new · ${e.counts.relocalise} re-localised · ${e.counts.same} same`;
  const m = S.match;
  $('match-error').textContent = m ? fmt(m.error, 3) + (m.is_new ? ' (new)' : '') : '—';
  $('match-visual').textContent = m ? fmt(m.visual_error, 3) : '—';
  $('match-pfh').textContent = m ? fmt(m.pfh_error, 3) : '—';
  $('match-sda').textContent = m ? fmt(m.sda_error, 3) : '—';
  $('match-template').textContent = m ? m.template_id : '—';
  $('match-shift').textContent = m ? m.visual_shift : '—';
  $('match-templates').textContent = m ? m.num_templates : '—';
  $('match-used').textContent = m ? [m.visual_used ? 'vision' : null, m.tactile_used ? 'touch' : null].filter(Boolean).join(' + ') || 'none' : '—';
}

// ---- every daemon's status ----
function renderStatus() {
  const box = $('daemons');
  const list = S.status || [];
  if (list.length === 0) return;
  box.replaceChildren(...list.map((d) => {
    const card = document.createElement('div');
    card.className = 'daemon ' + d.colour;
    card.dataset.name = d.name;
    const head = document.createElement('div');
    const name = document.createElement('span'); name.className = 'name'; name.textContent = d.name;
    const state = document.createElement('span'); state.className = 'state ' + d.colour;
    state.textContent = d.stale ? `${d.state}, silent ${fmt(d.age_s, 0)} s` : d.state;
    head.append(name, state);
    card.append(head);
    if (d.message) { const m = document.createElement('div'); m.className = 'message'; m.textContent = d.message; card.append(m); }
    const dl = document.createElement('dl');
    for (const [k, v] of d.counters.concat(d.stats)) {
      const dt = document.createElement('dt'); dt.textContent = k;
      const dd = document.createElement('dd'); dd.textContent = Number.isInteger(v) ? v : fmt(v, 2);
      // Counters of something that went wrong are amber when not 0; a cycle without contact is normal.
      if (v && k !== 'cycles_without_contact' && /error|drop|overflow|without|jump|out_of_order|superseded|miss|stale|gap/.test(k)) {
        dd.className = 'nonzero';
      }
      dl.append(dt, dd);
    }
    card.append(dl);
    return card;
  }));
}

function renderServer(server) {
  if (!server) return;
  S.server = server;
  const meta = S.meta || {};
  let text = `${server.clients}/${server.max_clients} live pages, ${server.dropped} updates dropped for slow pages` +
    `, ${meta.decode_errors || 0} undecodable messages`;
  if (meta.last_decode_error) text += ` (last: ${meta.last_decode_error})`;
  $('server').textContent = text;
}

function renderAll() {
  renderMap(); renderCamera(); drawWhiskers(); renderEvent(); renderStatus(); renderServer(S.server);
  $('clock').textContent = S.meta ? timeText(S.meta.now) : '—';
}

function take(sections) {
  for (const [k, v] of Object.entries(sections)) S[k] = v;
}

// ---- live: Server-Sent Events ----
function live() {
  const es = new EventSource('/api/events');
  es.addEventListener('snapshot', (ev) => {
    const snap = JSON.parse(ev.data);
    take(snap);
    $('connection').textContent = 'connected'; $('connection').className = 'pill live';
    renderAll();
  });
  es.addEventListener('delta', (ev) => {
    const d = JSON.parse(ev.data);
    if (d.v <= S.v) return;  // already in the snapshot this page has
    take(d);
    if (d.map || d.pose || d.trail) renderMap();
    if (d.camera) renderCamera();
    if (d.whiskers) drawWhiskers();
    if (d.event || d.match) renderEvent();
    if (d.status) renderStatus();
    if (d.meta) { $('clock').textContent = timeText(S.meta.now); renderServer(S.server); }
  });
  es.addEventListener('server', (ev) => renderServer(JSON.parse(ev.data)));
  es.onerror = () => { $('connection').textContent = 'reconnecting…'; $('connection').className = 'pill lost'; };
}

// The whole state from the server; an answer that is not the state (a log that changed under the
// viewer) is thrown with the server's reason, which the page shows.
async function snapshot(url) {
  const res = await fetch(url);
  const body = await res.json().catch(() => ({}));
  if (!res.ok) throw new Error(body.error || `HTTP ${res.status}`);
  return body;
}

function showError(e) {
  $('connection').textContent = 'error: ' + (e && e.message ? e.message : e);
  $('connection').className = 'pill lost';
}

// ---- a log: the slider asks the server for the state at a time ----
let fetching = false, pending = null;
async function showAt(t) {
  sliderT = Math.round(t);
  $('slider-time').textContent = `${fmt((sliderT - log.start) / 1e6, 1)} / ${fmt((log.end - log.start) / 1e6, 1)} s`;
  if (fetching) { pending = sliderT; return; }
  fetching = true;
  try {
    const snap = await snapshot(`/api/snapshot?t=${sliderT}`);
    S.v = -1;
    take(snap);
    renderAll();
  } catch (e) {
    showError(e);
  } finally {
    fetching = false;
    if (pending !== null) { const p = pending; pending = null; showAt(p); }
  }
}

function logMode(server) {
  log = server.log;
  $('timeline').hidden = false;
  const slider = $('slider');
  slider.max = 1000;
  const timeOf = () => log.start + (log.end - log.start) * slider.value / 1000;
  slider.addEventListener('input', () => showAt(timeOf()));
  let timer = null;
  $('play').addEventListener('click', () => {
    if (timer) { clearInterval(timer); timer = null; $('play').textContent = '▶'; return; }
    if (Number(slider.value) >= 1000) slider.value = 0;
    $('play').textContent = '⏸';
    const stepUs = 200000;  // real time: 0.2 s of log every 0.2 s
    timer = setInterval(() => {
      const t = Math.min(log.end, sliderT + stepUs);
      slider.value = Math.round(1000 * (t - log.start) / Math.max(1, log.end - log.start));
      showAt(t);
      if (t >= log.end) { clearInterval(timer); timer = null; $('play').textContent = '▶'; }
    }, 200);
  });
  showAt(log.end);
}

async function start() {
  const snap = await snapshot('/api/snapshot');
  mode = snap.server.mode;
  $('mode').textContent = mode === 'log' ? 'log ' + snap.server.log.file.split('/').pop() : 'live';
  $('mode').className = 'pill ' + mode;
  if (mode === 'log') {
    $('connection').textContent = `${snap.server.log.events} messages`;
    logMode(snap.server);
  } else {
    take(snap);
    renderAll();
    live();
  }
}

start().catch(showError);
