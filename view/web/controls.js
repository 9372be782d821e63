// candi's page, shared by candi view (the server renders: viewer.js) and candi publish (the
// browser renders with WebGL2: site.js): the camera, input, settings, layers, measuring,
// annotations, provenance and the shared-view address. Vectors are arrays [x, y, z] in world
// metres. A backend object renders:
//   load() -> Promise of the scene (view/source.h's JSON)
//   update(camera, settings)   the image to converge to (called once per animation frame at most)
//   pick(x, y) -> Promise of {hit, point, hits: [{layer, point, depth}]}   shown points only
//   png() -> Promise of the converged PNG (a Blob) or null
//   section(request) -> Promise of the reply (candi view only; absent: no section export)
//   api: what it adds to window.candiViewer (tests and scripts)
'use strict';
window.CandiPage = function (backend) {
  const $ = (id) => document.getElementById(id);
  const canvas = $('view');

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
  let dirty = false;

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

  // ---- the backend ------------------------------------------------------------------------
  function changed() { dirty = true; }
  function pump() {
    if (dirty && camera) {
      dirty = false;
      backend.update(clone(camera), clone(settings));
      scheduleAddress();
    }
    requestAnimationFrame(pump);
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
  function pixelOf(e) {
    const rect = canvas.getBoundingClientRect();
    return [(e.clientX - rect.left) * camera.width / rect.width, (e.clientY - rect.top) * camera.height / rect.height];
  }
  canvas.addEventListener('dblclick', (e) => {
    const [x, y] = pixelOf(e);
    backend.pick(x, y).then((m) => { if (m.hit) flyTo(m.point); });
  });
  // In measure mode a click (a press and release that did not move) picks a point.
  let press = null;
  canvas.addEventListener('pointerdown', (e) => { press = { x: e.clientX, y: e.clientY, button: e.button }; });
  canvas.addEventListener('pointerup', (e) => {
    if (!press || press.button !== 0 || !$('measure').checked) return;
    if (Math.hypot(e.clientX - press.x, e.clientY - press.y) > 3) return;
    const [x, y] = pixelOf(e);
    measureAt(x, y);
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
    else if (e.key === 'm' || e.key === 'M') { $('measure').checked = !$('measure').checked; }
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
  // view.json: the camera (render/view_json.h) and, under "settings", what else makes the image:
  // L, seed, the layers' shares by name, the clipping (candi render --view applies them).
  function viewJson() {
    return JSON.stringify({ projection: camera.projection, width: camera.width, height: camera.height, eye: camera.eye,
      target: camera.target, up: camera.up, fov_y_deg: camera.fov_y_deg, ortho_height: camera.ortho_height,
      near: camera.near, settings: { repeat_level: settings.repeat_level, seed: settings.seed, opaque: settings.opaque,
        point_size: settings.point_size, background: settings.background, brightness: settings.brightness,
        layers: settings.layers, layer_names: scene.layers.map((l) => l.name), clip: settings.clip } }, null, 2) + '\n';
  }
  $('save-view').addEventListener('click', () => download('view.json', new Blob([viewJson()], { type: 'application/json' })));
  $('save-png').addEventListener('click', () => backend.png().then((blob) => {
    if (blob) download(scene.title + '.png', blob);
    else $('status').textContent = 'the image has not converged yet: wait for ' + settings.repeat_level + ' ensembles';
  }));

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

  // ---- measuring: picked points in survey coordinates ----------------------------------------
  const measurements = [];  // { hits: the pick's hits (nearest first), index: the one used }
  const at = (m) => m.hits[m.index];
  const layerName = (i) => (scene.layers[i] ? scene.layers[i].name : 'layer ' + i);
  function measureAt(x, y) {
    return backend.pick(x, y).then((m) => {
      if (!m.hit) { $('status').textContent = 'nothing shown under that pixel'; return null; }
      const last = measurements[measurements.length - 1];
      if (last && at(last).point.every((v, k) => v === m.hits[0].point[k])) return last;  // a double click
      measurements.push({ hits: m.hits, index: 0 });
      showMeasurements();
      return measurements[measurements.length - 1];
    });
  }
  // Between consecutive points: distance, horizontal distance, height difference.
  function segments() {
    const out = [];
    for (let i = 1; i < measurements.length; ++i) {
      const a = at(measurements[i - 1]).point, b = at(measurements[i]).point, d = sub(b, a);
      out.push({ from: i, to: i + 1, distance: norm(d), horizontal: Math.hypot(d[0], d[1]), dz: d[2] });
    }
    return out;
  }
  function showMeasurements() {
    const body = $('measurements').querySelector('tbody');
    body.textContent = '';
    measurements.forEach((m, i) => {
      const tr = document.createElement('tr');
      const h = at(m);
      // Points coloured by a field: its value, read back from the point's colour by the server.
      const field = scene.legend && 'value' in h ? ' · ' + scene.legend.field + ' ' + (h.value === null ? 'grey (outside or none)'
        : Number(h.value).toPrecision(4) + ' ± ' + Number(h.value_half_width).toPrecision(1)) : '';
      const cells = [String(i + 1), layerName(h.layer) + (m.hits.length > 1 ? ' (' + (m.index + 1) + '/' + m.hits.length + ')' : '') + field,
        h.point[0].toFixed(3), h.point[1].toFixed(3), h.point[2].toFixed(3)];
      for (const c of cells) { const td = document.createElement('td'); td.textContent = c; tr.appendChild(td); }
      const td = document.createElement('td');
      if (m.hits.length > 1) {
        const behind = document.createElement('button');
        behind.textContent = 'behind';
        behind.title = 'the next shown layer\'s point under the same pixel';
        behind.addEventListener('click', () => { m.index = (m.index + 1) % m.hits.length; showMeasurements(); });
        td.appendChild(behind);
      }
      const remove = document.createElement('button');
      remove.textContent = '×';
      remove.addEventListener('click', () => { measurements.splice(i, 1); showMeasurements(); });
      td.appendChild(remove);
      tr.appendChild(td);
      body.appendChild(tr);
    });
    const lines = segments().map((g) => g.from + '→' + g.to + ': ' + g.distance.toFixed(3) + ' m · horizontal ' +
      g.horizontal.toFixed(3) + ' · Δz ' + (g.dz >= 0 ? '+' : '') + g.dz.toFixed(3));
    const total = segments().reduce((t, g) => t + g.distance, 0);
    $('measure-summary').textContent = lines.join('\n') + (lines.length > 1 ? '\ntotal ' + total.toFixed(3) + ' m' : '');
    $('measure-summary').style.whiteSpace = 'pre-line';
    overlayKey = '';
  }
  function measurementsCsv() {
    let out = 'point,layer,x,y,z,distance_m,horizontal_m,dz_m\n';
    const g = segments();
    measurements.forEach((m, i) => {
      const h = at(m), s = i > 0 ? g[i - 1] : null;
      out += [i + 1, JSON.stringify(layerName(h.layer)), ...h.point.map((v) => v.toFixed(4)),
        s ? s.distance.toFixed(4) : '', s ? s.horizontal.toFixed(4) : '', s ? s.dz.toFixed(4) : ''].join(',') + '\n';
    });
    return out;
  }
  function measurementsJson() {
    return JSON.stringify({ frame: 'world (survey) coordinates, metres', archive: scene.title,
      points: measurements.map((m, i) => ({ index: i + 1, layer: layerName(at(m).layer), point: at(m).point })),
      segments: segments() }, null, 2) + '\n';
  }
  $('measure-csv').addEventListener('click', () => download('measurements.csv', new Blob([measurementsCsv()], { type: 'text/csv' })));
  $('measure-json').addEventListener('click', () => download('measurements.json', new Blob([measurementsJson()], { type: 'application/json' })));
  $('measure-clear').addEventListener('click', () => { measurements.length = 0; showMeasurements(); });

  // The overlay: measured points and the lines between them, projected as the server projects.
  const overlay = $('overlay'), octx = overlay.getContext('2d');
  let overlayKey = '';
  function project(p) {
    const b = basis(), d = sub(p, camera.eye);
    const x = dot(d, b.r), y = -dot(d, b.u), z = dot(d, b.f);
    if (camera.projection === 'orthographic') {
      const s = camera.height / camera.ortho_height;
      return [camera.width / 2 + s * x, camera.height / 2 + s * y];
    }
    if (z <= camera.near) return null;
    const focal = 0.5 * camera.height / Math.tan(camera.fov_y_deg * Math.PI / 360);
    return [camera.width / 2 + focal * x / z, camera.height / 2 + focal * y / z];
  }
  function drawOverlay() {
    if (camera) {
      const key = JSON.stringify([camera, measurements.map((m) => m.index), measurements.length, annotations.length]);
      if (key !== overlayKey) {
        overlayKey = key;
        overlay.width = camera.width;
        overlay.height = camera.height;
        octx.clearRect(0, 0, overlay.width, overlay.height);
        octx.strokeStyle = '#ff0';
        octx.fillStyle = '#ff0';
        octx.lineWidth = 1.5;
        octx.font = '12px sans-serif';
        annotations.forEach((a, i) => {
          const q = project(a.position);
          if (!q) return;
          octx.strokeStyle = '#0cf';
          octx.fillStyle = '#0cf';
          octx.beginPath(); octx.arc(q[0], q[1], 6, 0, 2 * Math.PI); octx.stroke();
          octx.fillText((i + 1) + '. ' + a.title, q[0] + 9, q[1] + 4);
        });
        octx.strokeStyle = '#ff0';
        octx.fillStyle = '#ff0';
        let prev = null;
        measurements.forEach((m, i) => {
          const q = project(at(m).point);
          if (q && prev) { octx.beginPath(); octx.moveTo(prev[0], prev[1]); octx.lineTo(q[0], q[1]); octx.stroke(); }
          if (q) {
            octx.beginPath(); octx.arc(q[0], q[1], 4, 0, 2 * Math.PI); octx.stroke();
            octx.fillText(String(i + 1), q[0] + 6, q[1] - 6);
          }
          prev = q;
        });
      }
    }
    requestAnimationFrame(drawOverlay);
  }

  // ---- clipping and sections ----------------------------------------------------------------
  let baseClip = [];        // the clipping candi view was started with (--clip-box, --clip-plane)
  let beforeSection = null; // the camera before "show the section"
  const boxIds = ['clip-min-x', 'clip-min-y', 'clip-min-z', 'clip-max-x', 'clip-max-y', 'clip-max-z'];
  function boxPlanes() {
    if (!$('clip-box').checked) return [];
    const v = boxIds.map((id) => Number($(id).value));
    if (v.some((x) => !Number.isFinite(x)) || v[0] > v[3] || v[1] > v[4] || v[2] > v[5]) {
      $('section-summary').textContent = 'clip box: each minimum must be a number below its maximum';
      return [];
    }
    return [[v[0], v[1], v[2], 1, 0, 0], [v[0], v[1], v[2], 0, 1, 0], [v[0], v[1], v[2], 0, 0, 1],
            [v[3], v[4], v[5], -1, 0, 0], [v[3], v[4], v[5], 0, -1, 0], [v[3], v[4], v[5], 0, 0, -1]];
  }
  function sectionPlane() {
    const mode = $('section-plane').value, t = Number($('section-thickness').value);
    if (!(t > 0)) throw new Error('the thickness must be > 0 m');
    const pts = measurements.map((m) => at(m).point);
    if (mode === 'view') {
      const f = sub(camera.target, camera.eye);
      const h = Math.hypot(f[0], f[1]) > 1e-9 ? [f[0], f[1], 0] : [0, 1, 0];
      return { point: camera.target.slice(), normal: unit(h), thickness: t };
    }
    if (mode === 'two') {
      if (pts.length < 2) throw new Error('measure two points first');
      const a = pts[pts.length - 2], b = pts[pts.length - 1], d = [b[0] - a[0], b[1] - a[1], 0];
      if (norm(d) < 1e-9) throw new Error('the two points coincide in plan');
      return { point: a.slice(), normal: unit(cross([0, 0, 1], d)), thickness: t };
    }
    if (pts.length < 1) throw new Error('measure a point first');
    return { point: pts[pts.length - 1].slice(), normal: [0, 0, 1], thickness: t };
  }
  function updateClip() {
    const planes = baseClip.concat(boxPlanes());
    if ($('section-show').checked) {
      try {
        const s = sectionPlane(), n = s.normal, h = s.thickness / 2;
        planes.push([...sub(s.point, mul(n, h)), ...n], [...add(s.point, mul(n, h)), ...mul(n, -1)]);
      } catch (e) {
        $('section-summary').textContent = e.message;
        $('section-show').checked = false;
      }
    }
    settings.clip = planes;
    changed();
  }
  function onSectionShow() {
    if ($('section-show').checked) {
      let s;
      try { s = sectionPlane(); } catch (e) { $('section-summary').textContent = e.message; $('section-show').checked = false; return; }
      beforeSection = clone(camera);
      // Orthographic, looking along the normal: the drawing's chainage to the right (candi section's image).
      const d = norm(sub(camera.eye, camera.target));
      camera.ortho_height = camera.projection === 'orthographic' ? camera.ortho_height : 2 * d * Math.tan(camera.fov_y_deg * Math.PI / 360);
      camera.projection = 'orthographic';
      camera.target = s.point;
      camera.eye = sub(s.point, mul(s.normal, d));
      camera.up = Math.abs(s.normal[2]) > 0.999 ? [0, 1, 0] : [0, 0, 1];
      syncControls();
    } else if (beforeSection) {
      camera = beforeSection;
      beforeSection = null;
      fitCanvas(true);
      syncControls();
    }
    updateClip();
  }
  function blobLink(name, blob) {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = name;
    a.textContent = name;
    return a;
  }
  let lastSection = null;
  function exportSection(s) {
    $('section-summary').textContent = 'cutting the section…';
    return backend.section({ point: s.point, normal: s.normal, thickness: s.thickness }).then((m) => {
      if (m.type !== 'section') { $('section-summary').textContent = 'section failed: ' + m.message; return m; }
      lastSection = m;
      const png = Uint8Array.from(atob(m.png_base64), (c) => c.charCodeAt(0));
      // The SVG shows the image too: embedded, so the file stands alone.
      const svg = m.svg.split('"section.png"').join('"data:image/png;base64,' + m.png_base64 + '"');
      const box = $('section-summary');
      box.textContent = m.summary.layers.map((l) => l.name + ': ' + l.points + ' points, ' + l.lines + ' lines, ' +
        l.length_m.toFixed(2) + ' m' + (l.in_plane ? ' (in the plane)' : '')).join('\n') + '\n';
      box.style.whiteSpace = 'pre-line';
      [['section.dxf', m.dxf, 'application/dxf'], ['section.svg', svg, 'image/svg+xml'], ['section.csv', m.csv, 'text/csv'],
       ['section.png', png, 'image/png']].forEach(([name, data, type], i) => {
        if (i) box.appendChild(document.createTextNode(' · '));
        box.appendChild(blobLink(name, new Blob([data], { type })));
      });
      return m;
    });
  }
  $('section-export').addEventListener('click', () => {
    try { exportSection(sectionPlane()); } catch (e) { $('section-summary').textContent = e.message; }
  });
  $('clip-box').addEventListener('input', updateClip);
  boxIds.forEach((id) => $(id).addEventListener('change', updateClip));
  $('section-show').addEventListener('input', onSectionShow);
  ['section-plane', 'section-thickness'].forEach((id) => $(id).addEventListener('change', () => { if ($('section-show').checked) updateClip(); }));

  // For tests and scripts (the DevTools protocol reads these).
  const api = {
    viewJson,
    dirty: () => dirty,
    camera: () => clone(camera),
    settings: () => clone(settings),
    setSettings: (s) => { Object.assign(settings, s); syncControls(); syncLayers(); changed(); },
    setCamera: (c) => { Object.assign(camera, c); changed(); },
    pngBase64: () => backend.png().then((blob) => new Promise((resolve) => {
      if (!blob) return resolve('');
      const reader = new FileReader();
      reader.onload = () => resolve(String(reader.result).split(',')[1]);
      reader.readAsDataURL(blob);
    })),
    pick: (x, y) => backend.pick(x, y),
    measureAt,
    measurements: () => measurements.map((m) => ({ layer: layerName(at(m).layer), point: at(m).point, hits: m.hits.length })),
    segments,
    measurementsCsv,
    stepBehind: (i) => { const m = measurements[i]; m.index = (m.index + 1) % m.hits.length; showMeasurements(); },
    exportSection: (s) => exportSection(s),
    lastSection: () => lastSection,
    project,
    address: () => shareAddress(),
    annotations: () => annotations.slice(),
    flyToAnnotation: (i) => openAnnotation(i),
    status: () => $('status').textContent,
  };
  window.candiViewer = Object.assign(api, backend.api || {});

  // ---- the shared view: camera and settings in the address's fragment -----------------------
  // #view=<base64url of {"camera": view.json's fields, "settings": the settings above}>: the
  // address reopens the same camera, L, layers' shares, clipping, background and brightness.
  // "Save view" writes the same JSON; candi render --view reads its camera, layers and clipping.
  function viewState() { return JSON.parse(viewJson()); }
  function encode(obj) {
    const bytes = new TextEncoder().encode(JSON.stringify(obj));
    let text = '';
    for (const b of bytes) text += String.fromCharCode(b);
    return btoa(text).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
  }
  function decode(text) {
    const raw = atob(text.replace(/-/g, '+').replace(/_/g, '/'));
    return JSON.parse(new TextDecoder().decode(Uint8Array.from(raw, (c) => c.charCodeAt(0))));
  }
  function shareAddress() { return location.href.split('#')[0] + '#view=' + encode(viewState()); }
  let addressTimer = null;
  function scheduleAddress() {
    clearTimeout(addressTimer);
    addressTimer = setTimeout(() => history.replaceState(null, '', location.pathname + location.search + '#view=' + encode(viewState())), 300);
  }
  function readAddress() {
    const m = /#view=([A-Za-z0-9_-]+)/.exec(location.hash);
    if (!m) return null;
    try { return decode(m[1]); } catch (e) { $('status').textContent = 'the address\'s view is not readable: ' + e.message; return null; }
  }
  const finite = (v) => typeof v === 'number' && Number.isFinite(v);
  const vec3 = (v) => Array.isArray(v) && v.length === 3 && v.every(finite);
  // Takes what is valid of a shared or saved view; names what is not.
  function applyShared(v) {
    const bad = [];
    const c = v.camera || v;
    if (c.projection === 'perspective' || c.projection === 'orthographic') camera.projection = c.projection;
    for (const k of ['eye', 'target', 'up']) { if (vec3(c[k])) camera[k] = c[k].slice(); else if (k in c) bad.push('camera.' + k); }
    for (const k of ['fov_y_deg', 'ortho_height', 'near']) { if (finite(c[k]) && c[k] > 0) camera[k] = c[k]; else if (k in c) bad.push('camera.' + k); }
    const s = v.settings || {};
    if (Number.isInteger(s.repeat_level) && s.repeat_level >= 1 && s.repeat_level <= 10000) settings.repeat_level = s.repeat_level;
    if (finite(s.point_size) && s.point_size >= 1 && s.point_size <= 64) settings.point_size = s.point_size;
    if (vec3(s.background) && s.background.every((x) => x >= 0 && x <= 255)) settings.background = s.background.map(Math.round);
    if (s.brightness === 'auto' || s.brightness === 'none' || (finite(s.brightness) && s.brightness > 0 && s.brightness <= 100)) settings.brightness = s.brightness;
    if (typeof s.opaque === 'boolean') settings.opaque = s.opaque;
    if (Array.isArray(s.layers)) {
      if (s.layers.length === scene.layers.length && s.layers.every((f) => finite(f) && f >= 0 && f <= 16)) settings.layers = s.layers.slice();
      else bad.push('settings.layers');
    }
    if (Array.isArray(s.clip)) {
      if (s.clip.length <= 16 && s.clip.every((p) => Array.isArray(p) && p.length === 6 && p.every(finite))) settings.clip = s.clip.map((p) => p.slice());
      else bad.push('settings.clip');
    }
    if (bad.length) $('status').textContent = 'the shared view\'s ' + bad.join(', ') + ' not valid: left as they were';
  }
  $('share').addEventListener('click', () => {
    const address = shareAddress();
    history.replaceState(null, '', address);
    if (navigator.clipboard) navigator.clipboard.writeText(address).catch(() => {});
    $('status').textContent = 'this view\'s address is in the address bar (and copied)';
  });

  // ---- annotations and provenance ------------------------------------------------------------
  // The scene's labelled points: markers on the overlay and a list; a click flies to its view.
  let annotations = [];
  function openAnnotation(i) {
    const a = annotations[i];
    if (!a) return;
    $('annotation-text').textContent = a.title + (a.text ? ': ' + a.text : '');
    if (typeof a.view === 'string') {  // a scene view's name
      const v = scene.views.find((x) => x.name === a.view);
      if (v) { resetView(v.camera); return; }
      flyTo(a.position);
    } else if (a.view && typeof a.view === 'object') {  // an inline camera
      applyShared({ camera: a.view });
      fitCanvas(true);
      syncControls();
      changed();
    } else {
      flyTo(a.position);
    }
  }
  function describeCrs(c) {
    if (!c) return 'none stated (local coordinates)';
    return c.label || c.definition || c.to || JSON.stringify(c);
  }
  function buildProvenance() {
    const p = scene.provenance || {};
    annotations = (Array.isArray(p.annotations) ? p.annotations : []).filter((a) => a && typeof a.title === 'string' && vec3(a.position));
    const list = $('annotations');
    list.textContent = '';
    annotations.forEach((a, i) => {
      const b = document.createElement('button');
      b.textContent = (i + 1) + '. ' + a.title;
      b.className = 'annotation';
      b.addEventListener('click', () => openAnnotation(i));
      list.appendChild(b);
    });
    $('annotations-box').hidden = annotations.length === 0;
    const box = $('provenance');
    box.textContent = '';
    const line = (text, cls) => { const d = document.createElement('div'); d.textContent = text; if (cls) d.className = cls; box.appendChild(d); return d; };
    line('CRS: ' + describeCrs(p.crs));
    if (typeof p.licence === 'string') line('Licence: ' + p.licence);
    const layers = Array.isArray(p.layers) ? p.layers : [];
    if (!layers.length) line('No provenance: a render archive or point files (a build directory records it).', 'hint');
    for (const l of layers) {
      const d = line('', 'layer');
      const head = document.createElement('div');
      head.className = 'name';
      head.textContent = l.name + ' · ' + (l.scanned === true ? 'measured' : l.scanned === false ? 'reconstructed' : 'unknown') + (l.kind ? ' (' + l.kind + ')' : '');
      d.appendChild(head);
      if (l.method) { const m = document.createElement('div'); m.className = 'hint'; m.textContent = l.method; d.appendChild(m); }
      if (Array.isArray(l.sources) && l.sources.length) {
        const m = document.createElement('div');
        m.className = 'hint';
        m.textContent = 'from ' + l.sources.slice(0, 6).map((x) => x.file).join(', ') + (l.sources.length > 6 ? ' and ' + (l.sources.length - 6) + ' more' : '');
        d.appendChild(m);
      }
    }
  }
  // The colouring by a field (candi view FILE --colour-by): its scale, range and grey's counts.
  function buildLegend() {
    const l = scene.legend;
    const box = $('legend');
    box.textContent = '';
    box.hidden = !l;
    if (!l) return;
    const div = (text, cls) => { const d = document.createElement('div'); d.textContent = text; if (cls) d.className = cls; box.appendChild(d); return d; };
    const swatch = (colour) => { const b = document.createElement('span'); b.className = 'swatch'; b.style.background = colour; return b; };
    // 3 significant digits without trailing zeros after the point (100 stays 100; 0.0100 is 0.01).
    const num = (v) => {
      const t = Number(v).toPrecision(3);
      if (t.includes('e')) return t.replace(/\.?0+e/, 'e');
      return t.includes('.') ? t.replace(/\.?0+$/, '') : t;
    };
    div(l.field, 'name');
    if (Array.isArray(l.classes)) {
      for (const c of l.classes) { const d = div(' ' + c.code + ' ' + c.name); d.prepend(swatch(c.colour)); }
    } else {
      const bar = div('', 'scale');
      bar.style.background = 'linear-gradient(to right, ' + l.stops.join(', ') + ')';
      const ticks = div('', 'ticks');
      const mid = l.scale === 'diverging' && l.lo === -l.hi ? 0 : (l.lo + l.hi) / 2;
      for (const v of [l.lo, mid, l.hi]) { const t = document.createElement('span'); t.textContent = num(v); ticks.appendChild(t); }
    }
    const grey = [];
    if (!Array.isArray(l.classes)) grey.push(l.outside.toLocaleString() + ' outside');
    if (l.undefined > 0) grey.push(l.undefined.toLocaleString() + ' without a value');
    if (grey.length) { const d = div(' ' + grey.join(', '), 'hint'); d.prepend(swatch(l.grey)); }
  }
  // A click (press and release without moving) on a marker opens it.
  canvas.addEventListener('pointerup', (e) => {
    if (!press || press.button !== 0 || $('measure').checked || !annotations.length) return;
    if (Math.hypot(e.clientX - press.x, e.clientY - press.y) > 3) return;
    const [x, y] = pixelOf(e);
    annotations.forEach((a, i) => { const q = project(a.position); if (q && Math.hypot(q[0] - x, q[1] - y) < 10) openAnnotation(i); });
  });
  function showTitle() {
    const p = scene.preview;
    $('title').textContent = scene.title + ' · ' + (p ? 'preview: 1 point in ' + p.every + ' of ' +
      p.points.toLocaleString() + ' points, the rest packing' : scene.points.toLocaleString() + ' points');
  }
  backend.load().then((s) => {
    scene = s;
    document.title = (document.body.classList.contains('site') ? '' : 'candi view · ') + s.title;
    showTitle();
    // candi view FILE: the whole archive replaces a preview (the layers' counts change).
    backend.rescene = (next) => {
      scene.points = next.points;
      scene.chunks = next.chunks;
      scene.preview = next.preview;
      next.layers.forEach((l, i) => { if (scene.layers[i] && scene.layers[i].name === l.name) scene.layers[i].points = l.points; });
      showTitle();
      buildLayers();
    };
    settings = clone(s.settings);
    for (const v of s.views) { const o = document.createElement('option'); o.value = v.name; o.textContent = v.name; $('views').appendChild(o); }
    if (!settings.layers) settings.layers = s.layers.map(() => 1);
    baseClip = settings.clip || [];
    settings.clip = baseClip.slice();
    boxIds.forEach((id, k) => { $(id).value = (k < 3 ? s.bounds.min[k] : s.bounds.max[k - 3]).toFixed(3); });
    camera = clone(s.first_view);
    const shared = readAddress();
    if (shared) applyShared(shared);
    buildLayers();
    buildProvenance();
    buildLegend();
    // The first view's own size when the window has it (so the first image is candi render's).
    fitCanvas(true);
    syncControls();
    if (!backend.section) $('section-export').hidden = true;
    requestAnimationFrame(pump);
    requestAnimationFrame(drawOverlay);
  }).catch((e) => { $('status').textContent = String(e.message || e); });
};
