// The web console's page: reads /api/events (Server-Sent Events, one JSON state each) and
// draws it. Every text from the bus goes in with textContent, never as HTML.
// What it shows is also kept in data- attributes, for scripts (the browser test,
// tools/web_console/browser_test): #pose data-x/y/z (as displayed) and data-utime (of the
// POSE shown), #steps data-count (steps of the sequence shown), #seqhead data-state and
// data-submission, and on the #map canvas data-zones (names drawn), data-goal ("x y r"
// drawn) and data-view (the site-to-canvas transform drawMap used, see sx and sy there).
// #banner, shown only then, says why the stack will refuse this console's commands
// (commands.key_problem); #result holds each command's answer (refused: the executor's
// reason, in red).
// Playing back a log (rover_web --log, the state's "playback" is set), it asks for the
// state at the slider's time instead (/api/state?at=SECONDS) and sends no commands.
'use strict';
const $ = (id) => document.getElementById(id);
const fix = (v, d) => (v === null || v === undefined || !isFinite(v)) ? '-' : Number(v).toFixed(d);
let last = null;
let imageFrame = null;

function cell(row, text, cls, numeric) {
  const td = document.createElement('td');
  td.textContent = text;
  if (cls) td.className = cls;
  if (numeric) td.classList.add('num');
  row.appendChild(td);
  return td;
}

function kv(table, rows) {
  table.replaceChildren();
  for (const [k, v, cls] of rows) {
    const tr = table.insertRow();
    cell(tr, k);
    cell(tr, v, cls);
  }
}

// ---- the traverse: north up, east right ----
function drawMap(s) {
  const canvas = $('map');
  const ctx = canvas.getContext('2d');
  const W = canvas.width, H = canvas.height;
  ctx.fillStyle = '#111';
  ctx.fillRect(0, 0, W, H);
  // What to fit: the map, the paths, the rover, the zones and the goal.
  let minX = Infinity, maxX = -Infinity, minY = Infinity, maxY = -Infinity;
  const take = (x, y, r = 0) => {
    minX = Math.min(minX, x - r); maxX = Math.max(maxX, x + r);
    minY = Math.min(minY, y - r); maxY = Math.max(maxY, y + r);
  };
  const m = s.map;
  if (m && m.rows > 0) { take(m.origin_x, m.origin_y); take(m.origin_x + m.rows * m.cell_m, m.origin_y + m.cols * m.cell_m); }
  for (const p of [s.path, s.truth_path]) for (let i = 0; i + 1 < p.length; i += 2) take(p[i], p[i + 1]);
  if (s.pose) take(s.pose.x, s.pose.y, 2);
  if (s.truth) take(s.truth.x, s.truth.y, 2);
  for (const z of s.zones) {
    if (z.shape === 'circle') take(z.x, z.y, z.radius_m);
    else for (let i = 0; i + 1 < z.vertices.length; i += 2) take(z.vertices[i], z.vertices[i + 1]);
  }
  if (s.goal) take(s.goal.x, s.goal.y, s.goal.radius_m + 0.5);
  if (!isFinite(minX)) { minX = -3; maxX = 3; minY = -3; maxY = 3; }
  const pad = 0.5;
  minX -= pad; maxX += pad; minY -= pad; maxY += pad;
  const scale = Math.min(W / (maxY - minY), H / (maxX - minX));  // px per metre
  const cx = (minY + maxY) / 2, cy = (minX + maxX) / 2;
  const sx = (x, y) => W / 2 + (y - cx) * scale;   // screen x from site y (east)
  const sy = (x, y) => H / 2 - (x - cy) * scale;   // screen y from site x (north)
  canvas.dataset.view = JSON.stringify({ W, H, scale, cx, cy });
  canvas.dataset.zones = s.zones.map((z) => z.name).join(',');
  canvas.dataset.goal = s.goal ? s.goal.x + ' ' + s.goal.y + ' ' + s.goal.radius_m : '';

  // The traversability map.
  if (m && m.rows > 0) {
    const colours = ['#3b3f46', '#2f6b3a', '#8a7a2a', '#8e2b2b'];
    const c = m.cell_m * scale;
    for (let i = 0; i < m.rows; i++) {
      for (let j = 0; j < m.cols; j++) {
        const k = m.cells.charCodeAt(i * m.cols + j) - 48;
        ctx.fillStyle = colours[k] || '#000';
        const x0 = m.origin_x + (i + 1) * m.cell_m, y0 = m.origin_y + j * m.cell_m;
        ctx.fillRect(sx(x0, y0), sy(x0, y0), Math.ceil(c), Math.ceil(c));
      }
    }
  }
  // A 1 m grid.
  ctx.strokeStyle = 'rgba(255,255,255,0.08)';
  ctx.lineWidth = 1;
  ctx.beginPath();
  for (let y = Math.ceil(minY); y <= maxY; y++) { ctx.moveTo(sx(0, y), 0); ctx.lineTo(sx(0, y), H); }
  for (let x = Math.ceil(minX); x <= maxX; x++) { ctx.moveTo(0, sy(x, 0)); ctx.lineTo(W, sy(x, 0)); }
  ctx.stroke();
  // Keep-out zones.
  ctx.lineWidth = 2;
  for (const z of s.zones) {
    ctx.strokeStyle = '#ff5c8a';
    ctx.fillStyle = 'rgba(255,92,138,0.18)';
    ctx.beginPath();
    let lx, ly;
    if (z.shape === 'circle') {
      ctx.arc(sx(z.x, z.y), sy(z.x, z.y), z.radius_m * scale, 0, 2 * Math.PI);
      lx = z.x; ly = z.y;
    } else {
      const v = z.vertices;
      for (let i = 0; i + 1 < v.length; i += 2) ctx[i ? 'lineTo' : 'moveTo'](sx(v[i], v[i + 1]), sy(v[i], v[i + 1]));
      ctx.closePath();
      lx = v[0]; ly = v[1];
    }
    ctx.fill();
    ctx.stroke();
    ctx.fillStyle = '#ff9fbc';
    ctx.font = '12px sans-serif';
    ctx.fillText(z.name, sx(lx, ly) + 4, sy(lx, ly) - 4);
  }
  // The goal disc of a goto.
  if (s.goal) {
    const gx = sx(s.goal.x, s.goal.y), gy = sy(s.goal.x, s.goal.y);
    ctx.strokeStyle = '#7bd88f';
    ctx.fillStyle = 'rgba(123,216,143,0.2)';
    ctx.beginPath();
    ctx.arc(gx, gy, Math.max(3, s.goal.radius_m * scale), 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    ctx.beginPath();
    ctx.moveTo(gx - 6, gy); ctx.lineTo(gx + 6, gy); ctx.moveTo(gx, gy - 6); ctx.lineTo(gx, gy + 6);
    ctx.stroke();
  }
  // Paths.
  const line = (p, colour, dash) => {
    if (p.length < 4) return;
    ctx.strokeStyle = colour;
    ctx.setLineDash(dash);
    ctx.lineWidth = 2;
    ctx.beginPath();
    for (let i = 0; i + 1 < p.length; i += 2) ctx[i ? 'lineTo' : 'moveTo'](sx(p[i], p[i + 1]), sy(p[i], p[i + 1]));
    ctx.stroke();
    ctx.setLineDash([]);
  };
  line(s.truth_path, '#ff9f43', [6, 4]);
  line(s.path, '#4ea1ff', []);
  // The rover: a triangle along its heading (yaw 0 north, 90 east).
  const rover = (x, y, yawDeg, colour, size) => {
    const a = yawDeg * Math.PI / 180;
    const fx = Math.sin(a), fy = -Math.cos(a);      // forward on screen
    const px = sx(x, y), py = sy(x, y);
    ctx.fillStyle = colour;
    ctx.beginPath();
    ctx.moveTo(px + fx * size, py + fy * size);
    ctx.lineTo(px - fx * size * 0.6 - fy * size * 0.55, py - fy * size * 0.6 + fx * size * 0.55);
    ctx.lineTo(px - fx * size * 0.6 + fy * size * 0.55, py - fy * size * 0.6 - fx * size * 0.55);
    ctx.closePath();
    ctx.fill();
  };
  if (s.truth) rover(s.truth.x, s.truth.y, s.truth.yaw_deg, '#ff9f43', 9);
  if (s.pose) {
    const e = s.pose.ellipse_3sigma;
    ctx.strokeStyle = '#4ea1ff';
    ctx.fillStyle = 'rgba(78,161,255,0.25)';
    ctx.beginPath();
    ctx.ellipse(sx(s.pose.x, s.pose.y), sy(s.pose.x, s.pose.y), Math.max(2, e.major_m * scale),
                Math.max(2, e.minor_m * scale), (e.heading_deg - 90) * Math.PI / 180, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    rover(s.pose.x, s.pose.y, s.pose.yaw_deg, '#4ea1ff', 11);
  }
  $('scale').textContent = '1 m grid, ' + fix(scale, 0) + ' px/m; north up';
}

function drawSequence(s) {
  const st = s.status;
  const head = $('seqhead');
  const pre = $('seq');
  pre.replaceChildren();
  head.dataset.state = st ? st.state : '';
  head.dataset.submission = st ? st.submission_id : '';
  if (!st) { head.textContent = 'no sequence status heard'; return; }
  const cls = { running: 'ok', paused: 'warn', aborted: 'bad', rejected: 'bad', completed: 'ok' }[st.state] || '';
  head.replaceChildren();
  const b = document.createElement('b');
  b.textContent = st.state.toUpperCase();
  b.className = cls;
  head.appendChild(b);
  let text = ' ' + st.name + ' (#' + st.submission_id + ')  t=' + fix(st.elapsed_s, 1) + ' s  driven ' +
      fix(st.distance_m, 2) + ' m  VO failures ' + st.vo_failures;
  if (st.command_index >= 0) text += '  command ' + (st.command_index + 1) + '/' + st.num_commands + ' step ' + (st.step_index + 1);
  if (st.abort_reason) text += '  abort_reason=' + st.abort_reason;
  head.appendChild(document.createTextNode(text));
  const detail = document.createElement('div');
  detail.textContent = st.detail;
  head.appendChild(detail);
  const lines = s.sequence_text !== null ? s.sequence_text.replace(/\n$/, '').split('\n')
                                         : (st.command_text ? ['(text not heard) line ' + st.command_line + ': ' + st.command_text] : []);
  lines.forEach((l, i) => {
    const span = document.createElement('span');
    span.textContent = String(i + 1).padStart(3) + '  ' + l;
    if (s.sequence_text !== null && i + 1 === st.command_line &&
        (st.state === 'running' || st.state === 'paused' || st.state === 'aborted')) span.className = 'current';
    pre.appendChild(span);
  });
  const cur = pre.querySelector('.current');
  if (cur) cur.scrollIntoView({ block: 'nearest' });
}

function drawTables(s) {
  const p = s.pose, t = s.truth;
  const rows = [];
  const shown = $('pose').dataset;
  shown.x = p ? fix(p.x, 3) : ''; shown.y = p ? fix(p.y, 3) : ''; shown.z = p ? fix(p.z, 3) : '';
  shown.utime = p ? p.utime : '';
  if (p) {
    rows.push(['estimate', 'x ' + fix(p.x, 3) + '  y ' + fix(p.y, 3) + '  z ' + fix(p.z, 3) + ' m  yaw ' + fix(p.yaw_deg, 2) + ' deg']);
    rows.push(['', 'roll ' + fix(p.roll_deg, 2) + '  pitch ' + fix(p.pitch_deg, 2) + ' deg  source ' + p.source + ', site ' + p.site]);
    rows.push(['1-sigma', 'x ' + fix(p.sigma_x_m, 3) + '  y ' + fix(p.sigma_y_m, 3) + '  z ' + fix(p.sigma_z_m, 3) + ' m  yaw ' + fix(p.sigma_yaw_deg, 2) + ' deg']);
    rows.push(['3-sigma', fix(p.ellipse_3sigma.major_m, 3) + ' x ' + fix(p.ellipse_3sigma.minor_m, 3) + ' m ellipse']);
  } else rows.push(['estimate', 'no POSE heard', 'warn']);
  if (t) {
    rows.push(['truth', 'x ' + fix(t.x, 3) + '  y ' + fix(t.y, 3) + '  z ' + fix(t.z, 3) + ' m  yaw ' + fix(t.yaw_deg, 2) + ' deg  ' + t.soil]);
    if (p) rows.push(['error', fix(Math.hypot(p.x - t.x, p.y - t.y), 3) + ' m horizontal']);
  }
  kv($('pose'), rows);

  const v = s.vo, h = s.hazard, r = [];
  if (v) {
    const tail = (id) => '...' + String(id).slice(-3);
    r.push(['VO', v.status + '  frames ' + tail(v.from_frame) + ' -> ' + tail(v.to_frame) + '  inliers ' + v.inliers + ' of ' + v.tracked +
            ' tracked  ' + fix(v.ms_total, 0) + ' ms', v.status === 'ok' || v.status === 'baseline' ? 'ok' : 'warn']);
    r.push(['', 'updates ok ' + v.ok + ', failed ' + v.failed + (v.reason ? '  ' + v.reason : '')]);
  } else r.push(['VO', 'no VO_UPDATE heard']);
  if (h) {
    r.push(['hazard', h.state.toUpperCase() + (h.zone ? '  nearest zone ' + h.zone + ' ' + fix(h.clearance_m, 2) + ' m' : ''),
            h.state === 'safe' ? 'ok' : 'bad']);
    r.push(['tilt', 'roll ' + fix(h.roll_deg, 1) + '/' + fix(h.roll_limit_deg, 0) + '  pitch ' + fix(h.pitch_deg, 1) + '/' + fix(h.pitch_limit_deg, 0) + ' deg']);
    if (h.detail) r.push(['', h.detail]);
  } else r.push(['hazard', 'no HAZARD_STATUS heard']);
  // The set in force, drawn or not: a sequence's zones are cleared when the next one starts.
  // KEEPOUT_ZONES comes only when the set changes: a console started later learns from the
  // hazard monitor's status that it holds zones (the nearest one).
  r.push(['zones', s.zones.length ? s.zones.map((z) => z.name).join(', ')
                   : h && h.zone ? 'none heard from the executor; the hazard monitor holds zones, nearest ' + h.zone
                                 : 'none in force']);
  if (s.map) r.push(['map', s.map.rows + 'x' + s.map.cols + ' cells of ' + s.map.cell_m + ' m: unsafe ' + s.map.unsafe +
                     ', caution ' + s.map.caution + ', safe ' + s.map.safe + ', unknown ' + s.map.unknown]);
  kv($('vohaz'), r);

  const steps = $('steps').tBodies[0];
  steps.replaceChildren();
  $('steps').dataset.count = s.step_count;
  $('stepcount').textContent = s.status ? s.step_count + ' in this sequence' + (s.step_count > s.steps.length ? ', the last ' + s.steps.length + ' below' : '') : '';
  for (const st of s.steps.slice().reverse()) {
    const tr = steps.insertRow();
    cell(tr, (st.command_index + 1) + '.' + (st.step_index + 1));
    cell(tr, fix(st.commanded_m, 3) + ' m ' + fix(st.commanded_deg, 1) + ' deg', '', true);
    cell(tr, fix(st.measured_m, 3) + ' m ' + fix(st.measured_deg, 1) + ' deg', '', true);
    cell(tr, fix(st.slip_pct, 1) + ' %', Math.abs(st.slip_pct) > 40 ? 'bad' : '', true);
    cell(tr, st.vo);
  }

  const procs = $('procs').tBodies[0];
  procs.replaceChildren();
  for (const pr of s.processes) {
    const tr = procs.insertRow();
    cell(tr, pr.name);
    cell(tr, pr.state, pr.state === 'ok' ? 'ok' : pr.state === 'degraded' ? 'warn' : 'bad');
    cell(tr, fix(pr.age_s, 1) + ' s ago', '', true);
    cell(tr, String(pr.dropped), pr.dropped > 0 ? 'warn' : '', true);
    cell(tr, pr.detail);
  }

  drawImage(s);
  $('cmdstate').textContent = s.playback ? 'Playback of a log: commands are off.'
      : s.commands.enabled
      ? 'Commands need the operator secret' + (s.commands.signed ? ' and are signed with the deployment key.' : ' (no key: unsigned).')
      : 'Read-only: rover_web was started without an operator secret.';
  $('bus').textContent = s.playback ? '' : s.bus;
  $('clock').textContent = 'rover time ' + fix(s.rover_time_s, 1) + ' s, ' + s.messages + ' messages';
}

// The NAVCAM image of the state: the newest frame it holds, or none. A playback moved to
// before the first frame has none, and the frame shown before (from a later time) must go.
function drawImage(s) {
  const img = $('navcam');
  if (!s.image) {
    imageFrame = null;
    img.hidden = true;
    img.removeAttribute('src');
    $('imginfo').textContent = s.playback ? 'no STEREO_FRAME at or before this time' : 'no STEREO_FRAME heard';
    return;
  }
  if (s.image.frame_id === imageFrame) return;
  imageFrame = s.image.frame_id;
  img.src = 'api/image.png?frame=' + encodeURIComponent(imageFrame) +
      (s.playback ? '&at=' + encodeURIComponent(s.playback.at_s) : '');
  img.hidden = false;
  $('imginfo').textContent = 'frame ' + s.image.frame_id + ' (' + s.image.purpose + '), ' + s.image.width + 'x' +
      s.image.height + ' ' + s.image.encoding + ', right exposed ' + (s.image.pair_skew_us / 1000).toFixed(3) +
      ' ms after left';
}

// A console whose commands the stack will refuse (no key on a signed stack, a key that
// does not verify the stack's messages) says so above everything.
function drawBanner(s) {
  const banner = $('banner');
  const problem = !s.playback && s.commands && s.commands.key_problem;
  banner.hidden = !problem;
  banner.textContent = problem ? 'Commands will be refused: ' + problem : '';
}

function render(s) {
  last = s;
  drawMap(s);
  drawSequence(s);
  drawTables(s);
  drawBanner(s);
}

function connect() {
  const es = new EventSource('api/events');
  es.onopen = () => { $('conn').textContent = 'live'; $('conn').className = ''; };
  es.onerror = () => { $('conn').textContent = 'disconnected (retrying)'; $('conn').className = 'bad'; };
  es.onmessage = (ev) => {
    try { render(JSON.parse(ev.data)); } catch (e) { $('conn').textContent = 'bad state: ' + e; $('conn').className = 'bad'; }
  };
}

async function command(path, body) {
  const result = $('result');
  result.textContent = '...';
  result.className = '';
  try {
    const res = await fetch(path, { method: 'POST', headers: { 'X-Rover-Secret': $('secret').value, 'Content-Type': 'text/plain' }, body });
    const text = await res.text();
    result.textContent = res.status + ': ' + text.trim();
    result.className = res.ok ? 'ok' : 'bad';
  } catch (e) {
    result.textContent = 'failed: ' + e;
    result.className = 'bad';
  }
}

// ---- playback: the slider is the log's time; play moves it at the chosen speed ----
const playback = { timer: null, busy: false, wanted: null };

async function showAt(t) {
  playback.wanted = t;
  if (playback.busy) return;  // the newest wish is fetched when the request in flight ends
  playback.busy = true;
  while (playback.wanted !== null) {
    const at = playback.wanted;
    playback.wanted = null;
    try {
      const res = await fetch('api/state?at=' + encodeURIComponent(at.toFixed(3)));
      if (!res.ok) throw new Error(res.status + ': ' + (await res.text()).trim());
      render(await res.json());
      $('conn').textContent = 'playback'; $('conn').className = '';
    } catch (e) { $('conn').textContent = 'playback: ' + e; $('conn').className = 'bad'; }
  }
  playback.busy = false;
}

function stopPlaying() {
  clearInterval(playback.timer);
  playback.timer = null;
  $('play').textContent = 'Play';
}

function startPlayback(s) {
  const p = s.playback, slider = $('slider');
  $('playbar').hidden = false;
  $('conn').textContent = 'playback';
  $('plog').textContent = p.log;
  slider.min = p.first_s; slider.max = p.last_s; slider.value = p.at_s;
  const label = () => { $('ptime').textContent = 'log time ' + fix(slider.value, 1) + ' s (' + fix(slider.value - p.first_s, 1) + ' of ' + fix(p.last_s - p.first_s, 1) + ')'; };
  label();
  slider.oninput = () => { label(); showAt(Number(slider.value)); };
  $('play').onclick = () => {
    if (playback.timer) return stopPlaying();
    if (Number(slider.value) >= p.last_s) slider.value = p.first_s;  // from the start again
    $('play').textContent = 'Pause';
    const tick_s = 0.2;
    playback.timer = setInterval(() => {
      const next = Math.min(p.last_s, Number(slider.value) + tick_s * Number($('speed').value));
      slider.value = next;
      label();
      showAt(next);
      if (next >= p.last_s) stopPlaying();
    }, tick_s * 1000);
  };
  for (const id of ['submit', 'pause', 'resume', 'abort', 'text', 'secret']) $(id).disabled = true;
}

$('submit').onclick = () => command('api/submit?name=web', $('text').value);
$('pause').onclick = () => command('api/pause', '');
$('resume').onclick = () => command('api/resume', '');
$('abort').onclick = () => { if (confirm('Abort the running sequence? The rover stops.')) command('api/abort', ''); };
window.addEventListener('resize', () => { if (last) drawMap(last); });
let initial = null;
try { initial = JSON.parse($('initial-state').textContent); render(initial); } catch (e) { /* the events will draw it */ }
if (initial && initial.playback) startPlayback(initial); else connect();
