// candi view: the page. The server renders (SPBR on its CPU); this page sends the camera and the
// settings, and shows the frames it gets back. Vectors are arrays [x, y, z] in world metres.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const token = new URLSearchParams(location.search).get('token') || '';
  const canvas = $('view');
  const ctx = canvas.getContext('2d');

  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm = (a) => Math.sqrt(dot(a, a));
  const unit = (a) => mul(a, 1 / norm(a));

  let scene = null;
  let camera = null;        // view.json fields
  let settings = null;      // the protocol's settings
  let socket = null;
  let seq = 0, dirty = false, viewSeq = 0;
  const stats = { framesReceived: 0, lastFrame: null, lastPng: null, sentAt: {}, latencies: [], drawnSeq: -1, drawnFrame: 0 };

  // ---- camera -----------------------------------------------------------------------------
  function clone(c) { return JSON.parse(JSON.stringify(c)); }
  function basis() {  // right, true up and forward of the camera
    const f = unit(sub(camera.target, camera.eye));
    const r = unit(cross(f, camera.up));
    return { f, r, u: cross(r, f) };
  }
  function metresPerPixel() {
    if (camera.projection === 'orthographic') return camera.ortho_height / camera.height;
    const d = norm(sub(camera.target, camera.eye));
    return 2 * d * Math.tan(camera.fov_y_deg * Math.PI / 360) / camera.height;
  }
  // Rotates v about the unit axis k by angle a (Rodrigues).
  function rotate(v, k, a) {
    const c = Math.cos(a), s = Math.sin(a);
    return add(add(mul(v, c), mul(cross(k, v), s)), mul(k, dot(k, v) * (1 - c)));
  }
  function orbit(dx, dy) {
    const up = unit(camera.up);
    let d = sub(camera.eye, camera.target);
    d = rotate(d, up, -dx * 0.005);
    const r = unit(cross(d, up));
    const d2 = rotate(d, r, -dy * 0.005);
    // Never over the pole: the view direction stays off the up axis.
    if (Math.abs(dot(unit(d2), up)) < 0.995) d = d2;
    camera.eye = add(camera.target, d);
    changed();
  }
  function pan(dx, dy) {
    const b = basis(), m = metresPerPixel();
    const shift = add(mul(b.r, -dx * m), mul(b.u, dy * m));
    camera.eye = add(camera.eye, shift);
    camera.target = add(camera.target, shift);
    changed();
  }
  function zoom(factor) {
    if (camera.projection === 'orthographic') {
      camera.ortho_height = Math.min(1e7, Math.max(1e-6, camera.ortho_height * factor));
    } else {
      const d = sub(camera.eye, camera.target);
      if (norm(d) * factor < 1e-4 || norm(d) * factor > 1e8) return;
      camera.eye = add(camera.target, mul(d, factor));
      camera.near = Math.max(1e-6, 1e-4 * norm(d) * factor);
    }
    changed();
  }
  let flight = null;
  function flyTo(point) {
    const from = { eye: camera.eye, target: camera.target, h: camera.ortho_height };
    const d = sub(camera.eye, camera.target);
    const to = { target: point, eye: add(point, mul(d, 0.5)), h: camera.ortho_height * 0.5 };
    const start = performance.now();
    if (flight) cancelAnimationFrame(flight);
    const step = (now) => {
      const t = Math.min(1, (now - start) / 400), s = t * t * (3 - 2 * t);
      camera.target = add(from.target, mul(sub(to.target, from.target), s));
      camera.eye = add(from.eye, mul(sub(to.eye, from.eye), s));
      camera.ortho_height = from.h + (to.h - from.h) * s;
      camera.near = Math.max(1e-6, 1e-4 * norm(sub(camera.eye, camera.target)));
      changed();
      flight = t < 1 ? requestAnimationFrame(step) : null;
    };
    flight = requestAnimationFrame(step);
  }
  function resetView(view) {
    camera = clone(view || scene.first_view);
    fitCanvas(true);
    syncControls();
    changed();
  }
  function fitCanvas(force) {
    const w = Math.max(16, Math.min(4096, Math.round(canvas.clientWidth)));
    const h = Math.max(16, Math.min(4096, Math.round(canvas.clientHeight)));
    if (force || w !== camera.width || h !== camera.height) {
      // Keep the vertical extent: the field of view (or ortho height) stays, the width follows.
      camera.width = w;
      camera.height = h;
      canvas.width = w;
      canvas.height = h;
      changed();
    }
  }

  // ---- protocol ---------------------------------------------------------------------------
  function changed() { dirty = true; }
  function send(message) {
    if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
  }
  function pump() {
    if (dirty && socket && socket.readyState === WebSocket.OPEN) {
      dirty = false;
      seq += 1;
      stats.sentAt[seq] = performance.now();
      viewSeq = seq;
      send({ type: 'view', seq, camera, settings });
    }
    requestAnimationFrame(pump);
  }
  function connect() {
    const url = (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws?token=' + encodeURIComponent(token);
    socket = new WebSocket(url);
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => { $('status').textContent = 'connected'; changed(); };
    socket.onclose = () => { $('status').textContent = 'disconnected: reload the page to reconnect'; };
    socket.onmessage = (event) => {
      if (typeof event.data === 'string') return onText(JSON.parse(event.data));
      onFrame(event.data);
    };
  }
  function onText(m) {
    if (m.type === 'pick' && m.hit) flyTo(m.point);
    if (m.type === 'error') $('status').textContent = 'server: ' + m.message;
  }
  function onFrame(buffer) {
    const view = new DataView(buffer);
    const n = view.getUint32(0, true);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n)));
    const blob = new Blob([new Uint8Array(buffer, 4 + n)], { type: header.format === 'png' ? 'image/png' : 'image/jpeg' });
    stats.framesReceived += 1;
    const arrival = stats.framesReceived;
    if (stats.sentAt[header.seq] !== undefined && header.ensembles > 0 && !stats.latencies[header.seq]) {
      stats.latencies[header.seq] = performance.now() - stats.sentAt[header.seq];
    }
    createImageBitmap(blob).then((bitmap) => {
      // Decoding finishes out of order (a PNG after the JPEG that followed it): show a frame only
      // if none that arrived after it is shown.
      if (arrival < stats.drawnFrame) { bitmap.close(); return; }
      stats.drawnFrame = arrival;
      stats.drawnSeq = header.seq;
      ctx.drawImage(bitmap, 0, 0);
      bitmap.close();
      stats.lastFrame = header;
      if (header.converged) stats.lastPng = blob;
      const k = header.ensembles, L = header.repeat_level;
      $('bar').style.width = (100 * k / L).toFixed(1) + '%';
      $('status').textContent = (header.converged ? 'converged: ' : 'converging: ') + k + ' / ' + L + ' ensembles · ' +
        header.render_ms.toFixed(0) + ' ms · gain ' + header.gain.toFixed(2);
    });
  }

  // ---- input ------------------------------------------------------------------------------
  let drag = null;
  const pointers = new Map();
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey };
    canvas.focus();
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!pointers.has(e.pointerId)) return;
    const last = pointers.get(e.pointerId);
    if (pointers.size === 2) {  // pinch: zoom by the change of distance, pan by the midpoint
      const [a, b] = [...pointers.values()];
      const before = Math.hypot(a.x - b.x, a.y - b.y), mid0 = [(a.x + b.x) / 2, (a.y + b.y) / 2];
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      const [c, d] = [...pointers.values()];
      const after = Math.hypot(c.x - d.x, c.y - d.y), mid1 = [(c.x + d.x) / 2, (c.y + d.y) / 2];
      if (after > 0 && before > 0) zoom(before / after);
      pan(mid1[0] - mid0[0], mid1[1] - mid0[1]);
      return;
    }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    const dx = e.clientX - last.x, dy = e.clientY - last.y;
    if (drag && drag.pan) pan(dx, dy); else orbit(dx, dy);
  });
  const release = (e) => { pointers.delete(e.pointerId); if (pointers.size === 0) drag = null; };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('wheel', (e) => { e.preventDefault(); zoom(Math.exp(e.deltaY * 0.001)); }, { passive: false });
  canvas.addEventListener('dblclick', (e) => {
    const rect = canvas.getBoundingClientRect();
    seq += 1;
    send({ type: 'pick', seq, x: (e.clientX - rect.left) * camera.width / rect.width,
           y: (e.clientY - rect.top) * camera.height / rect.height });
  });
  window.addEventListener('keydown', (e) => {
    if (e.target !== canvas && e.target !== document.body) return;
    const step = 20;
    const moves = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
    if (moves[e.key]) { const [x, y] = moves[e.key]; if (e.shiftKey) pan(x, y); else orbit(x, y); e.preventDefault(); }
    else if (e.key === '+' || e.key === '=') zoom(0.8);
    else if (e.key === '-' || e.key === '_') zoom(1.25);
    else if (e.key === 'r' || e.key === 'R') resetView();
    else if (e.key === 'o' || e.key === 'O') { $('projection').value = camera.projection === 'orthographic' ? 'perspective' : 'orthographic'; onProjection(); }
    else if (e.key === 't' || e.key === 'T') { $('opaque').checked = !$('opaque').checked; readSettings(); }
  });
  window.addEventListener('resize', () => fitCanvas(false));

  // ---- controls ---------------------------------------------------------------------------
  const hex = (c) => '#' + c.map((v) => v.toString(16).padStart(2, '0')).join('');
  const rgb = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
  function syncControls() {
    $('repeat-level').value = settings.repeat_level;
    $('point-size').value = settings.point_size;
    $('point-size-value').textContent = settings.point_size;
    $('background').value = hex(settings.background);
    $('opaque').checked = settings.opaque;
    $('projection').value = camera.projection;
    if (settings.brightness === 'auto' || settings.brightness === 'none') $('brightness').value = settings.brightness;
    else { $('brightness').value = 'gain'; $('gain').value = settings.brightness; $('gain').hidden = false; }
    canvas.style.background = hex(settings.background);
  }
  function readSettings() {
    const L = Math.round(Number($('repeat-level').value));
    if (L >= 1 && L <= 10000) settings.repeat_level = L;
    settings.point_size = Number($('point-size').value);
    $('point-size-value').textContent = settings.point_size;
    settings.background = rgb($('background').value);
    settings.opaque = $('opaque').checked;
    const b = $('brightness').value;
    $('gain').hidden = b !== 'gain';
    const g = Number($('gain').value);
    settings.brightness = b === 'gain' ? (g > 0 && g <= 100 ? g : 1) : b;
    canvas.style.background = hex(settings.background);
    changed();
  }
  function onProjection() {
    const p = $('projection').value;
    if (p === camera.projection) return;
    // Keep what is seen at the target: the ortho height equals the perspective view's height there.
    const d = norm(sub(camera.target, camera.eye));
    if (p === 'orthographic') camera.ortho_height = 2 * d * Math.tan(camera.fov_y_deg * Math.PI / 360);
    else camera.eye = add(camera.target, mul(unit(sub(camera.eye, camera.target)), camera.ortho_height / (2 * Math.tan(camera.fov_y_deg * Math.PI / 360))));
    camera.projection = p;
    changed();
  }
  ['repeat-level', 'point-size', 'background', 'opaque', 'brightness', 'gain'].forEach((id) => $(id).addEventListener('input', readSettings));
  $('projection').addEventListener('change', onProjection);
  $('reset').addEventListener('click', () => resetView());
  $('views').addEventListener('change', () => {
    const v = scene.views.find((x) => x.name === $('views').value);
    resetView(v ? v.camera : null);
    if (v) { settings.opaque = !!v.opaque; syncControls(); }
  });
  function download(name, blob) {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = name;
    a.click();
    setTimeout(() => URL.revokeObjectURL(a.href), 1000);
  }
  function viewJson() {
    return JSON.stringify({ projection: camera.projection, width: camera.width, height: camera.height, eye: camera.eye,
      target: camera.target, up: camera.up, fov_y_deg: camera.fov_y_deg, ortho_height: camera.ortho_height,
      near: camera.near }, null, 2) + '\n';
  }
  $('save-view').addEventListener('click', () => download('view.json', new Blob([viewJson()], { type: 'application/json' })));
  $('save-png').addEventListener('click', () => {
    if (stats.lastPng && stats.lastFrame && stats.lastFrame.converged) download(scene.title + '.png', stats.lastPng);
    else $('status').textContent = 'the image has not converged yet: wait for ' + settings.repeat_level + ' ensembles';
  });

  // ---- layers: visibility, points share (opacity), focus --------------------------------------
  const shown = [];  // the share each layer had before it was hidden
  function buildLayers() {
    const box = $('layers');
    box.textContent = '';
    scene.layers.forEach((l, i) => {
      shown[i] = settings.layers[i] > 0 ? settings.layers[i] : 1;
      const div = document.createElement('div');
      div.className = 'layer';
      div.innerHTML = '<label><input type="checkbox" class="visible"> <span class="name"></span></label>' +
        '<div class="meta"></div><label>points ×<input type="range" class="share" min="0.05" max="3" step="0.05">' +
        '<output class="share-value"></output></label><button class="focus" title="this layer at full share, ' +
        'the others dimmed">focus</button>';
      div.querySelector('.name').textContent = l.name;
      div.querySelector('.meta').textContent = (l.kind ? l.kind + ' · ' : '') + l.points.toLocaleString() + ' points';
      div.querySelector('.visible').id = 'layer-visible-' + i;
      div.querySelector('.share').id = 'layer-share-' + i;
      div.querySelector('.visible').addEventListener('input', (e) => {
        settings.layers[i] = e.target.checked ? shown[i] : 0;
        syncLayers();
        changed();
      });
      div.querySelector('.share').addEventListener('input', (e) => {
        shown[i] = Number(e.target.value);
        if (settings.layers[i] > 0) settings.layers[i] = shown[i];
        syncLayers();
        changed();
      });
      div.querySelector('.focus').addEventListener('click', () => {
        const dim = Math.min(1, Math.max(0, Number($('dim').value) || 0));
        settings.layers = scene.layers.map((_, k) => (k === i ? 1 : (dim > 0 ? dim : 0)));
        settings.layers.forEach((f, k) => { if (f > 0) shown[k] = f; });
        syncLayers();
        changed();
      });
      box.appendChild(div);
    });
    syncLayers();
  }
  function syncLayers() {
    scene.layers.forEach((l, i) => {
      const f = settings.layers[i];
      $('layer-visible-' + i).checked = f > 0;
      $('layer-share-' + i).value = f > 0 ? f : shown[i];
      $('layer-share-' + i).parentElement.querySelector('output').textContent = (f > 0 ? f : shown[i]).toFixed(2);
    });
  }
  $('layers-all').addEventListener('click', () => {
    settings.layers = scene.layers.map(() => 1);
    settings.layers.forEach((_, k) => { shown[k] = 1; });
    syncLayers();
    changed();
  });

  // For tests and scripts (the DevTools protocol reads these).
  window.candiViewer = {
    stats, viewJson,
    // The seq of the last view sent, or -1 while a change waits to be sent.
    viewSeq: () => (dirty ? -1 : viewSeq),
    camera: () => clone(camera),
    settings: () => clone(settings),
    setSettings: (s) => { Object.assign(settings, s); syncControls(); syncLayers(); changed(); },
    setCamera: (c) => { Object.assign(camera, c); changed(); },
    pngBase64: () => new Promise((resolve) => {
      if (!stats.lastPng) return resolve('');
      const reader = new FileReader();
      reader.onload = () => resolve(String(reader.result).split(',')[1]);
      reader.readAsDataURL(stats.lastPng);
    }),
    canvasPixels: () => Array.from(ctx.getImageData(0, 0, canvas.width, canvas.height).data),
  };

  fetch('/api/scene?token=' + encodeURIComponent(token)).then((r) => {
    if (!r.ok) throw new Error('the server refused: ' + r.status + ' (open the address candi view printed)');
    return r.json();
  }).then((s) => {
    scene = s;
    document.title = 'candi view · ' + s.title;
    $('title').textContent = s.title + ' · ' + s.points.toLocaleString() + ' points';
    settings = clone(s.settings);
    for (const v of s.views) { const o = document.createElement('option'); o.value = v.name; o.textContent = v.name; $('views').appendChild(o); }
    if (!settings.layers) settings.layers = s.layers.map(() => 1);
    buildLayers();
    camera = clone(s.first_view);
    // The first view's own size when the window has it (so the first image is candi render's).
    fitCanvas(true);
    syncControls();
    connect();
    requestAnimationFrame(pump);
  }).catch((e) => { $('status').textContent = String(e.message || e); });
})();
