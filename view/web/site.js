// candi publish: the page's backend that renders in the visitor's browser. SPBR with WebGL2: per
// ensemble, that ensemble's points with a depth test into an 8-bit image; the ensembles' colours
// and hits are summed in a float32 target (sums of up to L 8-bit values are exact); the shown
// image is (gain * sum + (k - hits) * background) / k, rounded, as candi render's
// (render/spbr.h). The data (view/publish.h) streams in ensemble order: page k of every group
// (the points ensemble k draws at the site's L) before any page k + 1, groups in view and near
// first, within a budget of points; a Web Worker decodes the pages.
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);
  const canvas = $('view');
  const errors = [];
  function fail(message) {
    errors.push(message);
    $('errors').textContent = errors.slice(-6).join('\n') + (errors.length > 6 ? '\n(' + errors.length + ' problems in all)' : '');
  }
  const gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: false, preserveDrawingBuffer: true,
    premultipliedAlpha: false });
  const floatTargets = gl && gl.getExtension('EXT_color_buffer_float');
  if (!gl || !floatTargets) {
    const why = !gl ? 'this browser gives no WebGL2' : 'this browser cannot render to float32 targets (EXT_color_buffer_float)';
    $('status').textContent = why + ': the site cannot draw here';
    fail(why);
    window.candiViewer = { webgl2: !!gl, errors: () => errors.slice() };
    return;
  }

  // The slices each ensemble draws (render/archive.cc's EnsembleSlices): site_index.js.
  const ensembleSlices = window.CandiSiteIndex.ensembleSlices;

  // ---- GL programs -------------------------------------------------------------------------
  function compile(vs, fs) {
    const p = gl.createProgram();
    for (const [type, text] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, text);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      gl.attachShader(p, s);
    }
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }
  // A point: its 8-byte word as (lo, hi). q = word >> 24 (40 bits: x, y, z of bits.x, .y, .z);
  // the camera coordinates c = A q + b (A = R diag(step), b = R (min - eye), from doubles).
  const pointVs = `#version 300 es
  precision highp float; precision highp int;
  layout(location = 0) in uvec2 word;
  uniform ivec3 bits; uniform mat3 A; uniform vec3 b; uniform vec3 chunkMin; uniform vec3 step;
  uniform float focal, cx, cy, near, width, height, zmin, zmax, pointSize; uniform bool perspective;
  uniform int planes; uniform vec4 clip[16];
  flat out vec3 color;
  uint field(uint qlo, uint qhi, int s, int n) {
    if (n == 0) return 0u;
    uint mask = (1u << uint(n)) - 1u;
    if (s + n <= 32) return (qlo >> uint(s)) & mask;
    if (s >= 32) return (qhi >> uint(s - 32)) & mask;
    return ((qlo >> uint(s)) | (qhi << uint(32 - s))) & mask;
  }
  void main() {
    uint qlo = (word.x >> 24u) | (word.y << 8u), qhi = word.y >> 24u;
    vec3 q = vec3(float(field(qlo, qhi, 0, bits.x)), float(field(qlo, qhi, bits.x, bits.y)),
                  float(field(qlo, qhi, bits.x + bits.y, bits.z)));
    color = vec3(float((word.x >> 16u) & 255u), float((word.x >> 8u) & 255u), float(word.x & 255u)) / 255.0;
    vec3 c = A * q + b;
    gl_PointSize = pointSize;
    bool keep = c.z > near;
    vec3 p = chunkMin + q * step;
    for (int i = 0; i < 16; ++i) { if (i < planes && dot(clip[i].xyz, p) < clip[i].w) keep = false; }
    float s = perspective ? focal / c.z : focal;
    float u = cx + s * c.x, v = cy + s * c.y;
    // The pixel as candi's kernel takes it (floor; a square of side n from floor(u - n/2 + 1/2)),
    // placed at its centre: no subpixel snapping of the rasteriser can move it to a neighbour.
    u = floor(u - 0.5 * pointSize + 0.5) + 0.5 * pointSize;
    v = floor(v - 0.5 * pointSize + 0.5) + 0.5 * pointSize;
    gl_Position = keep ? vec4(2.0 * u / width - 1.0, 1.0 - 2.0 * v / height,
                              clamp(2.0 * (c.z - zmin) / (zmax - zmin) - 1.0, -1.0, 1.0), 1.0) : vec4(2.0, 2.0, 2.0, 1.0);
  }`;
  const pointFs = `#version 300 es
  precision highp float;
  flat in vec3 color; out vec4 outColor;
  void main() { outColor = vec4(color, 1.0); }`;
  const quadVs = `#version 300 es
  void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)); gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0); }`;
  const addFs = `#version 300 es
  precision highp float; uniform highp sampler2D acc; uniform highp sampler2D ens; out vec4 outColor;
  void main() { ivec2 p = ivec2(gl_FragCoord.xy); vec4 e = texelFetch(ens, p, 0);
    outColor = texelFetch(acc, p, 0) + vec4(floor(e.rgb * 255.0 + 0.5), e.a); }`;
  const showFs = `#version 300 es
  precision highp float; uniform highp sampler2D acc; uniform float k, gain; uniform vec3 background; out vec4 outColor;
  void main() { vec4 s = texelFetch(acc, ivec2(gl_FragCoord.xy), 0);
    vec3 v = clamp((gain * s.rgb + (k - s.a) * background) / k, 0.0, 255.0);
    outColor = vec4(floor(v + 0.5) / 255.0, 1.0); }`;
  const pointProgram = compile(pointVs, pointFs), addProgram = compile(quadVs, addFs), showProgram = compile(quadVs, showFs);
  const uniforms = (p, names) => Object.fromEntries(names.map((n) => [n, gl.getUniformLocation(p, n)]));
  const pu = uniforms(pointProgram, ['bits', 'A', 'b', 'chunkMin', 'step', 'focal', 'cx', 'cy', 'near', 'width', 'height', 'zmin', 'zmax',
    'pointSize', 'perspective', 'planes', 'clip']);
  const au = uniforms(addProgram, ['acc', 'ens']);
  const su = uniforms(showProgram, ['acc', 'k', 'gain', 'background']);
  const vao = gl.createVertexArray();

  // ---- targets -----------------------------------------------------------------------------
  let W = 0, H = 0, ensFbo, ensTex, depthRb, accTex = [], accFbo = [], accIndex = 0;
  function texture(internal, format, type) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texStorage2D(gl.TEXTURE_2D, 1, internal, W, H);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    return t;
  }
  function targets(w, h) {
    if (w === W && h === H) return;
    [ensTex, ...accTex].forEach((t) => t && gl.deleteTexture(t));
    [ensFbo, ...accFbo].forEach((f) => f && gl.deleteFramebuffer(f));
    if (depthRb) gl.deleteRenderbuffer(depthRb);
    W = w; H = h;
    ensTex = texture(gl.RGBA8);
    depthRb = gl.createRenderbuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, depthRb);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT32F, W, H);
    ensFbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, ensFbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, ensTex, 0);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depthRb);
    accTex = [texture(gl.RGBA32F), texture(gl.RGBA32F)];
    accFbo = accTex.map((t) => {
      const f = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, f);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
      return f;
    });
  }

  // ---- the data ------------------------------------------------------------------------------
  let site = null, origin = [0, 0, 0], chunks = [], groups = [];
  let budgetPoints = 0, heldPoints = 0, inFlight = 0, requests = 0, bytesReceived = 0, pagesLoaded = 0;
  const worker = new Worker('site_worker.js');
  const waiting = new Map();
  let nextId = 0;
  worker.onmessage = (e) => { const w = waiting.get(e.data.id); waiting.delete(e.data.id); w(e.data); };
  function decode(name, buffer, points, bytes) {
    return new Promise((resolve) => { const id = nextId++; waiting.set(id, resolve); worker.postMessage({ id, name, buffer, points, bytes }, [buffer]); });
  }
  const pageName = (g, k) => 'data/' + g + '/' + k + '.bin';
  // A response's body, read until it holds more than `most` bytes (then the download is stopped:
  // a file larger than site.json says is not this site's page, whatever it would grow to).
  async function readAtMost(r, most) {
    const declared = Number(r.headers.get('Content-Length'));
    if (r.headers.get('Content-Encoding') === null && declared > most) {
      throw new Error('is ' + declared + ' bytes, more than the ' + most + ' site.json allows: not this site\'s page');
    }
    const reader = r.body.getReader(), parts = [];
    let n = 0;
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      n += value.length;
      bytesReceived += value.length;
      if (n > most) {
        reader.cancel().catch(() => {});
        throw new Error('is more than the ' + most + ' bytes site.json allows: not this site\'s page (download stopped)');
      }
      parts.push(value);
    }
    const out = new Uint8Array(n);
    let at = 0;
    for (const part of parts) { out.set(part, at); at += part.length; }
    return out.buffer;
  }
  // Page k of group g: chunk-relative runs, one per chunk, in the file's order.
  function pageRuns(g, k) {
    const runs = [];
    for (let c = groups[g].chunks[0]; c < groups[g].chunks[1]; ++c) {
      const out = [];
      ensembleSlices(chunks[c], site.data.repeat_level, site.data.seed, k, 1, out);
      runs.push(out.length ? [out[0], out[1]] : [0, 0]);
    }
    return runs;
  }
  function loadPage(g, k) {
    const page = groups[g].pages[k];
    page.state = 'loading';
    inFlight += page.points;
    requests += 1;
    let counted = true;
    const landed = () => { if (counted) { inFlight -= page.points; requests -= 1; counted = false; } };
    const name = pageName(g, k);
    return fetch(name).then((r) => {
      if (!r.ok) throw new Error(name + ': HTTP ' + r.status + ' ' + r.statusText);
      // The gzip file, or its planes where a server decompressed them on the way.
      return readAtMost(r, Math.max(page.bytes, 8 * page.points));
    }).then((buffer) => {
      return decode(name, buffer, page.points, page.bytes);
    }).then((m) => {
      landed();
      if (m.error) throw new Error(m.error);
      if (page.state !== 'loading') return;  // evicted meanwhile
      page.words = m.words;
      page.vbo = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, page.vbo);
      gl.bufferData(gl.ARRAY_BUFFER, m.words, gl.STATIC_DRAW);
      let offset = 0;
      pageRuns(g, k).forEach(([b, e], i) => {
        if (e > b) chunks[groups[g].chunks[0] + i].segments.push({ begin: b, end: e, page, offset });
        offset += e - b;
      });
      page.state = 'loaded';
      heldPoints += page.points;
      pagesLoaded += 1;
      onData(k);
    }).catch((e) => {
      landed();
      page.state = 'failed';
      fail(String(e.message || e).startsWith(name) ? String(e.message || e) : name + ': ' + (e.message || e));
      onData(k);
    });
  }
  function evict(page) {
    if (page.vbo) gl.deleteBuffer(page.vbo);
    const gr = groups[page.group];
    for (let c = gr.chunks[0]; c < gr.chunks[1]; ++c) chunks[c].segments = chunks[c].segments.filter((s) => s.page !== page);
    heldPoints -= page.points;
    page.vbo = null; page.words = null; page.state = 'none';
  }

  // Priority of page k of group g: lower first. Ensemble order, then groups in view, then near.
  function groupDistance(g) {
    const cam = state.camera, b = groups[g].box;
    let d = 0;
    for (let a = 0; a < 3; ++a) { const x = cam.eye[a] - origin[a]; d += Math.max(0, b.min[a] - x, x - b.max[a]) ** 2; }
    return Math.sqrt(d);
  }
  function groupInView(g) {
    const box = groups[g].box;
    let left = 0, right = 0, top = 0, bottom = 0, behind = 0;
    for (let i = 0; i < 8; ++i) {
      const p = [i & 1 ? box.max[0] : box.min[0], i & 2 ? box.max[1] : box.min[1], i & 4 ? box.max[2] : box.min[2]];
      const q = projectLocal(p);
      if (!q) { behind++; continue; }
      if (q[0] < 0) left++; if (q[0] >= W) right++; if (q[1] < 0) top++; if (q[1] >= H) bottom++;
    }
    if (behind === 8) return false;
    if (behind > 0) return true;
    return !(left === 8 || right === 8 || top === 8 || bottom === 8);
  }
  function layerShown(g) {
    const f = state.settings.layers;
    for (let c = groups[g].chunks[0]; c < groups[g].chunks[1]; ++c) if (!f || f[chunks[c].layer] > 0) return true;
    return false;
  }
  // The loading order, ensemble by ensemble (page k of every shown group before any page k + 1),
  // the shown groups in rank order; walked from the first ensemble with a page still to load, so
  // a pump costs what it loads, not L x groups.
  let shownOrder = [], firstOpen = 0;
  function planOrder() {
    if (!state) return;
    const rank = groups.map((_, g) => ({ g, shown: layerShown(g), view: groupInView(g), d: groupDistance(g) }));
    rank.sort((a, b) => (b.shown - a.shown) || (b.view - a.view) || (a.d - b.d));
    const pos = new Array(groups.length);
    rank.forEach((r, i) => { pos[r.g] = i; groups[r.g].wanted = r.shown; });
    shownOrder = rank.filter((r) => r.shown).map((r) => r.g);
    firstOpen = 0;
    groups.forEach((gr, g) => { gr.rank = pos[g]; });
  }
  const priority = (g, k) => k * groups.length + groups[g].rank;
  function pump() {
    if (!state) return;
    let evictable = null;  // loaded pages, the lowest priority (hidden layers, then finest and far) last
    const L = site.data.repeat_level;
    // (An evicted page ranks below the one loaded instead: it never lies before firstOpen.)
    ensembles: for (let k = firstOpen; k < L; ++k) {
      let open = false;
      for (const g of shownOrder) {
        const page = groups[g].pages[k];
        if (page.state !== 'none') continue;
        open = true;
        if (requests >= 4) break ensembles;  // a few pages at a time, in the order planned
        if (page.points > budgetPoints) {
          // It can never fit: named once with the group's other such pages, and the pages after
          // it still load.
          let n = 0, most = 0;
          for (const p of groups[g].pages) {
            if (p.points > budgetPoints && p.state === 'none') { p.state = 'too large'; n += 1; most = Math.max(most, p.points); }
          }
          fail('data/' + g + '/: ' + n + (n === 1 ? ' page' : ' pages') + ' of up to ' + (most / 1e6).toFixed(2) +
            ' M points, more than the memory budget holds (' + (budgetPoints / 1e6).toFixed(2) + ' M): not loaded');
          continue;
        }
        if (heldPoints + inFlight + page.points > budgetPoints) {
          // Drop the finest pages of far groups first, while they rank below this one.
          if (!evictable) {
            evictable = [];
            groups.forEach((gr, h) => gr.pages.forEach((p, j) => {
              if (p.state === 'loaded') evictable.push({ p, q: gr.wanted ? priority(h, j) : Infinity });
            }));
            evictable.sort((a, b) => a.q - b.q);
          }
          const wp = priority(g, k);
          while (heldPoints + inFlight + page.points > budgetPoints && evictable.length &&
                 evictable[evictable.length - 1].q > wp) {
            evict(evictable.pop().p);
            restart();
          }
          if (heldPoints + inFlight + page.points > budgetPoints) break ensembles;  // the rest ranks lower still
        }
        loadPage(g, k);
      }
      if (!open && k === firstOpen) firstOpen = k + 1;
    }
    showProgress();
  }
  // Pages the image lacks that no wait brings: failed, larger than the budget, or in groups
  // site.json describes wrongly; as text, or '' when there are none.
  function missingPages() {
    let failed = 0, dropped = 0;
    for (const gr of groups) {
      if (gr.dropped) dropped += 1;
      else if (gr.wanted) for (const p of gr.pages) if (p.state === 'failed' || p.state === 'too large') failed += 1;
    }
    return [failed ? failed + (failed === 1 ? ' page' : ' pages') : '', dropped ? dropped + (dropped === 1 ? ' group' : ' groups') : '']
      .filter((t) => t).join(' and ');
  }
  let budgetReached = false;
  function showProgress() {
    let want = 0, have = 0, loadable = 0;
    for (const gr of groups) {
      if (!gr.wanted) continue;
      for (const p of gr.pages) {
        want += p.points;
        if (p.state === 'loaded') have += p.points;
        if (p.state !== 'failed' && p.state !== 'too large') loadable += p.points;
      }
    }
    $('bar').style.width = (want ? 100 * have / want : 100).toFixed(1) + '%';
    if (want && (have === want || heldPoints + inFlight >= budgetPoints) && !inFlight && allLoadedAt === null) allLoadedAt = performance.now();
    // Pages that could load but wait for room: the image is what the budget holds.
    budgetReached = have < loadable && !inFlight;
    progressText = (have === want ? 'all ' : '') + (have / 1e6).toFixed(2) + ' of ' + (want / 1e6).toFixed(2) + ' M points loaded (' +
      (bytesReceived / 1e6).toFixed(1) + ' MB)' + (budgetReached ? ' · memory budget reached' : '');
  }
  let progressText = '';

  // ---- drawing -------------------------------------------------------------------------------
  let state = null;        // {camera, settings}
  let drawn = 0;           // ensembles accumulated
  let firstGrey = null;    // the first ensemble's grey histogram (auto brightness)
  let gain = 1, changedAt = 0, firstImageAt = null, firstImageBytes = null, convergedAt = null, allLoadedAt = null;
  const stats = { images: 0, ensemblesDrawn: 0, pointsDrawn: 0 };
  function restart() { drawn = 0; firstGrey = null; convergedAt = null; }
  function onData(k) {
    // A page of ensemble k changes the image only if that ensemble was drawn (at the site's L, f <= 1).
    const L = effectiveL();
    const aligned = L === site.data.repeat_level && (state.settings.layers || []).every((f) => f <= 1);
    if (!aligned || k < drawn) restart();
    pump();
  }
  const effectiveL = () => (state.settings.opaque ? 1 : state.settings.repeat_level);
  let proj = null;
  function makeProjector() {
    const c = state.camera;
    const eye = c.eye.map((x, a) => x - origin[a]), target = c.target.map((x, a) => x - origin[a]);
    const f = norm3(sub3(target, eye));
    const r = norm3(cross3(f, c.up));
    const u = cross3(f, r);  // camera y (down)
    const R = [r, u, f];
    const focal = c.projection === 'orthographic' ? c.height / c.ortho_height : 0.5 * c.height / Math.tan(c.fov_y_deg * Math.PI / 360);
    proj = { R, eye, focal, cx: 0.5 * c.width, cy: 0.5 * c.height, perspective: c.projection !== 'orthographic', near: c.near };
    // Depths for the depth buffer: the archive's bounds along the view axis.
    const b = site.scene.bounds;
    let zmin = Infinity, zmax = -Infinity;
    for (let i = 0; i < 8; ++i) {
      const p = [0, 1, 2].map((a) => ((i >> a) & 1 ? b.max[a] : b.min[a]) - origin[a] - eye[a]);
      const z = dot3(f, p);
      zmin = Math.min(zmin, z); zmax = Math.max(zmax, z);
    }
    const pad = 1e-3 * (zmax - zmin) + 1e-6;
    proj.zmin = Math.min(zmin - pad, proj.perspective ? c.near : zmin - pad);
    proj.zmax = zmax + pad;
  }
  function projectLocal(p) {
    const d = sub3(p, proj.eye), c = proj.R.map((row) => dot3(row, d));
    if (proj.perspective && c[2] <= proj.near) return null;
    const s = proj.perspective ? proj.focal / c[2] : proj.focal;
    return [proj.cx + s * c[0], proj.cy + s * c[1], c[2]];
  }
  const sub3 = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const dot3 = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross3 = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const norm3 = (a) => { const n = Math.sqrt(dot3(a, a)); return [a[0] / n, a[1] / n, a[2] / n]; };

  function chunkVisible(c) {
    const ch = chunks[c];
    let left = 0, right = 0, top = 0, bottom = 0, behind = 0;
    for (let i = 0; i < 8; ++i) {
      const q = projectLocal([i & 1 ? ch.max[0] : ch.min[0], i & 2 ? ch.max[1] : ch.min[1], i & 4 ? ch.max[2] : ch.min[2]]);
      if (!q) { behind++; continue; }
      const m = state.settings.point_size + 1;
      if (q[0] < -m) left++; if (q[0] >= W + m) right++; if (q[1] < -m) top++; if (q[1] >= H + m) bottom++;
    }
    if (behind === 8) return false;
    if (behind > 0) return true;
    return !(left === 8 || right === 8 || top === 8 || bottom === 8);
  }
  // The draw ranges of ensemble e: [chunk, page, first, count] over the loaded segments.
  function ensembleRanges(e, out) {
    const L = effectiveL(), f = state.settings.layers, runs = [];
    for (let c = 0; c < chunks.length; ++c) {
      const ch = chunks[c];
      if (!ch) continue;
      const share = f ? f[ch.layer] : 1;
      if (!(share > 0) || !ch.segments.length || !ch.visible) continue;
      runs.length = 0;
      ensembleSlices(ch, L, state.settings.seed, e, share, runs);
      for (let i = 0; i < runs.length; i += 2) {
        for (const s of ch.segments) {
          const b = Math.max(runs[i], s.begin), en = Math.min(runs[i + 1], s.end);
          if (en > b) out.push(c, s.page, s.offset + b - s.begin, en - b);
        }
      }
    }
  }
  function clipPlanes() {
    const out = new Float32Array(64);
    const planes = (state.settings.clip || []).slice(0, 16);
    planes.forEach((p, i) => {
      const n = [p[3], p[4], p[5]], len = Math.hypot(...n);
      const pt = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
      out.set([n[0] / len, n[1] / len, n[2] / len, dot3(n, pt) / len], 4 * i);
    });
    return { out, count: planes.length };
  }
  function drawEnsemble(e) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, ensFbo);
    gl.viewport(0, 0, W, H);
    gl.clearColor(0, 0, 0, 0);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.useProgram(pointProgram);
    gl.bindVertexArray(vao);
    gl.enableVertexAttribArray(0);
    gl.uniform1f(pu.focal, proj.focal); gl.uniform1f(pu.cx, proj.cx); gl.uniform1f(pu.cy, proj.cy);
    gl.uniform1f(pu.near, proj.perspective ? proj.near : -1e30);
    gl.uniform1f(pu.width, W); gl.uniform1f(pu.height, H);
    gl.uniform1f(pu.zmin, proj.zmin); gl.uniform1f(pu.zmax, proj.zmax);
    gl.uniform1f(pu.pointSize, Math.round(state.settings.point_size));
    gl.uniform1i(pu.perspective, proj.perspective ? 1 : 0);
    const clip = clipPlanes();
    gl.uniform1i(pu.planes, clip.count);
    gl.uniform4fv(pu.clip, clip.out);
    const ranges = [];
    ensembleRanges(e, ranges);
    let chunk = -1, vbo = null;
    for (let i = 0; i < ranges.length; i += 4) {
      const c = ranges[i], page = ranges[i + 1];
      if (c !== chunk) {
        chunk = c;
        const ch = chunks[c];
        const b = proj.R.map((row) => dot3(row, sub3(ch.min, proj.eye)));
        // mat3 is column-major: column j is R * e_j * step_j.
        const A = [];
        for (let j = 0; j < 3; ++j) for (let r = 0; r < 3; ++r) A.push(proj.R[r][j] * ch.step[j]);
        gl.uniformMatrix3fv(pu.A, false, A);
        gl.uniform3fv(pu.b, b);
        gl.uniform3iv(pu.bits, ch.bits);
        gl.uniform3fv(pu.chunkMin, ch.min);
        gl.uniform3fv(pu.step, ch.step);
      }
      if (page.vbo !== vbo) {
        vbo = page.vbo;
        gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
        gl.vertexAttribIPointer(0, 2, gl.UNSIGNED_INT, 8, 0);
      }
      gl.drawArrays(gl.POINTS, ranges[i + 2], ranges[i + 3]);
      stats.pointsDrawn += ranges[i + 3];
    }
    gl.disable(gl.DEPTH_TEST);
    if (e === 0 && state.settings.brightness === 'auto') firstGrey = greyHistogram();
    // Accumulate: acc' = acc + round(255 * ensemble colour), hits in alpha.
    const from = accIndex, to = 1 - accIndex;
    gl.bindFramebuffer(gl.FRAMEBUFFER, accFbo[to]);
    gl.useProgram(addProgram);
    gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, accTex[from]);
    gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D, ensTex);
    gl.uniform1i(au.acc, 0); gl.uniform1i(au.ens, 1);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    accIndex = to;
    stats.ensemblesDrawn += 1;
  }
  function greyHistogram() {
    const px = new Uint8Array(4 * W * H);
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const h = new Float64Array(256);
    for (let i = 0; i < px.length; i += 4) if (px[i + 3]) h[Math.floor((299 * px[i] + 587 * px[i + 1] + 114 * px[i + 2] + 500) / 1000)]++;
    return h;
  }
  // render/spbr.cc's AutoBrightnessGain over the accumulated sums.
  function autoGain(k) {
    if (!firstGrey) return 1;
    let drawnPx = 0;
    for (const c of firstGrey) drawnPx += c;
    if (!drawnPx) return 1;
    let t = 255;
    for (let above = 0; t > 0; --t) { above += firstGrey[t]; if (above * 100 >= drawnPx) break; }
    gl.bindFramebuffer(gl.FRAMEBUFFER, accFbo[accIndex]);
    const s = new Float32Array(4 * W * H);
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.FLOAT, s);
    const greys = [];
    for (let i = 0; i < s.length; i += 4) if (s[i + 3] > 0) greys.push((0.299 * s[i] + 0.587 * s[i + 1] + 0.114 * s[i + 2]) / k);
    if (!greys.length) return 1;
    greys.sort((a, b) => a - b);
    const g = greys[greys.length - 1 - Math.floor((greys.length - 1) / 100)];
    if (!(g > 0)) return 1;
    return Math.max(1, Math.ceil(t / g * 100 - 1e-9) / 100);
  }
  function show(k) {
    const b = state.settings.brightness;
    gain = b === 'auto' ? (k === effectiveL() || k === 1 || k % 8 === 0 ? autoGain(k) : gain) : b === 'none' ? 1 : Number(b);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, W, H);
    gl.useProgram(showProgram);
    gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, accTex[accIndex]);
    gl.uniform1i(su.acc, 0);
    gl.uniform1f(su.k, k);
    gl.uniform1f(su.gain, gain);
    gl.uniform3fv(su.background, state.settings.background);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    stats.images += 1;
  }
  // An ensemble is drawn once the pages it needs that are wanted have arrived (or failed): at
  // the site's L, page e of every wanted group; otherwise whatever is loaded.
  function ensembleReady(e) {
    if (effectiveL() !== site.data.repeat_level) return true;
    for (const gr of groups) {
      if (!gr.wanted) continue;
      const p = gr.pages[e];
      if (p.state === 'loading' || (p.state === 'none' && heldPoints + inFlight + p.points <= budgetPoints)) return false;
    }
    return true;
  }
  function frame(now) {
    requestAnimationFrame(frame);
    if (!state) return;
    const L = effectiveL();
    if (drawn >= L) return;
    const moving = now - changedAt < 200;
    const start = performance.now();
    let any = false;
    while (drawn < L && ensembleReady(drawn)) {
      if (drawn === 0) {
        gl.bindFramebuffer(gl.FRAMEBUFFER, accFbo[accIndex]);
        gl.clearColor(0, 0, 0, 0);
        gl.clear(gl.COLOR_BUFFER_BIT);
        for (let c = 0; c < chunks.length; ++c) if (chunks[c]) chunks[c].visible = chunkVisible(c);
      }
      drawEnsemble(drawn);
      drawn += 1;
      any = true;
      // While the camera moves: the first ensembles only; at rest, ~30 ms of work a frame.
      if (moving || performance.now() - start > 30) break;
    }
    if (!any) return;
    show(drawn);
    if (firstImageAt === null) { firstImageAt = performance.now(); firstImageBytes = bytesReceived; }
    // "converged" only when every page the image wants is in (or left out by the memory budget).
    const missing = missingPages();
    if (drawn === L && !missing) convergedAt = performance.now();
    $('status').textContent = (drawn < L ? 'converging: ' : missing ? 'incomplete, ' + missing + ' missing (named below): '
      : budgetReached ? 'converged within the memory budget: ' : 'converged: ') + drawn + ' / ' + L + ' ensembles · gain ' +
      gain.toFixed(2) + ' · ' + progressText;
  }
  requestAnimationFrame(frame);

  // ---- picking: the shown points under a pixel, on the client -----------------------------------
  // Points packed coloured by a field: the value a picked colour stands for, as candi view's
  // server reads it (FieldLegend::ValueOfColour): the middle of the values drawn in that colour
  // and how far they reach either side; null for the grey (outside the range, or no value).
  let colourRuns = null;  // colour -> [first, last] sample of the legend's scale
  function valueOfColour(legend, colour) {
    if (Array.isArray(legend.classes)) {
      const c = legend.classes.find((k) => parseInt(k.colour.slice(1), 16) === colour);
      return { value: c ? c.code : null, value_half_width: 0 };
    }
    if (colour === parseInt(legend.grey.slice(1), 16)) return { value: null, value_half_width: 0 };
    if (!colourRuns) {
      colourRuns = new Map();
      for (const [c, first, last] of legend.runs) {
        const r = colourRuns.get(c);
        colourRuns.set(c, r ? [r[0], last] : [first, last]);
      }
    }
    const r = colourRuns.get(colour);
    const step = (legend.hi - legend.lo) / legend.steps;
    if (!r) {
      // A colour the samples skip lies, channel by channel, between the runs either side of one
      // step (FieldLegend::ValueOfColour).
      const ch = (c, s) => (c >> s) & 255;
      const between = (c, a, b, s) => (ch(a, s) <= ch(c, s) && ch(c, s) <= ch(b, s)) || (ch(b, s) <= ch(c, s) && ch(c, s) <= ch(a, s));
      for (let k = 0; k + 1 < legend.runs.length; ++k) {
        const a = legend.runs[k][0], b = legend.runs[k + 1][0];
        if (between(colour, a, b, 16) && between(colour, a, b, 8) && between(colour, a, b, 0)) {
          return { value: legend.lo + (legend.runs[k][2] + 0.5) * step, value_half_width: 0.5 * step };
        }
      }
      return { value: null, value_half_width: 0 };
    }
    return { value: legend.lo + 0.5 * (r[0] + r[1]) * step, value_half_width: 0.5 * (r[1] - r[0] + 2) * step };
  }
  function pick(x, y) {
    const px = Math.floor(x), py = Math.floor(y), L = effectiveL(), f = state.settings.layers;
    const clip = clipPlanes();
    const best = new Map();  // layer -> {depth, point}
    const runs = [];
    for (let c = 0; c < chunks.length; ++c) {
      const ch = chunks[c];
      if (!ch) continue;
      const share = f ? f[ch.layer] : 1;
      if (!(share > 0) || !ch.segments.length || !chunkVisible(c)) continue;
      runs.length = 0;
      for (let e = 0; e < L; ++e) ensembleSlices(ch, L, state.settings.seed, e, share, runs);
      const m = [(1 << ch.bits[0]) - 1, (1 << ch.bits[1]) - 1, (1 << ch.bits[2]) - 1];
      for (const s of ch.segments) {
        const w = s.page.words;
        for (let i = 0; i < runs.length; i += 2) {
          const b = Math.max(runs[i], s.begin), en = Math.min(runs[i + 1], s.end);
          for (let k = b; k < en; ++k) {
            const j = s.offset + k - s.begin, lo = w[2 * j], hi = w[2 * j + 1];
            // q: 40 bits; split without 32-bit overflow.
            const q = Math.floor(lo / 16777216) + hi * 256;
            const qx = q % (m[0] + 1), q1 = Math.floor(q / (m[0] + 1));
            const qy = q1 % (m[1] + 1), qz = Math.floor(q1 / (m[1] + 1)) % (m[2] + 1);
            const p = [ch.min[0] + qx * ch.step[0], ch.min[1] + qy * ch.step[1], ch.min[2] + qz * ch.step[2]];
            let kept = true;
            for (let t = 0; t < clip.count && kept; ++t) {
              const o = clip.out;
              if (o[4 * t] * p[0] + o[4 * t + 1] * p[1] + o[4 * t + 2] * p[2] < o[4 * t + 3]) kept = false;
            }
            if (!kept) continue;
            const uv = projectLocal(p);
            if (!uv || Math.floor(uv[0]) !== px || Math.floor(uv[1]) !== py) continue;
            const cur = best.get(ch.layer);
            if (!cur || uv[2] < cur.depth) {
              best.set(ch.layer, { layer: ch.layer, depth: uv[2], point: p.map((v, a) => v + origin[a]), colour: lo & 0xffffff });
            }
          }
        }
      }
    }
    const hits = [...best.values()].sort((a, b) => a.depth - b.depth);
    const legend = site.scene.legend;
    if (legend) for (const h of hits) Object.assign(h, valueOfColour(legend, h.colour));
    return Promise.resolve(hits.length ? { type: 'pick', hit: true, point: hits[0].point, depth: hits[0].depth, layer: hits[0].layer, hits }
      : { type: 'pick', hit: false, hits: [] });
  }

  function png() {
    if (!state || drawn < effectiveL()) return Promise.resolve(null);
    return new Promise((resolve) => canvas.toBlob(resolve, 'image/png'));
  }
  // The shown image, rows top first, RGB (tests compare it with candi render's PNG).
  function imageRgb() {
    const px = new Uint8Array(4 * W * H);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const out = new Uint8Array(3 * W * H);
    for (let y = 0; y < H; ++y) for (let x = 0; x < W; ++x) {
      const i = 4 * ((H - 1 - y) * W + x), o = 3 * (y * W + x);
      out[o] = px[i]; out[o + 1] = px[i + 1]; out[o + 2] = px[i + 2];
    }
    let text = '';
    for (let i = 0; i < out.length; i += 8192) text += String.fromCharCode.apply(null, out.subarray(i, i + 8192));
    return btoa(text);
  }

  let replan = null;
  window.CandiPage({
    load: () => fetch('site.json').then((r) => {
      if (!r.ok) throw new Error('site.json: HTTP ' + r.status + ': this folder is not a candi site');
      return readAtMost(r, 256e6).catch((e) => { throw new Error('site.json ' + e.message); });
    }).then((buffer) => {
      let json;
      try { json = JSON.parse(new TextDecoder().decode(buffer)); } catch (e) { throw new Error('site.json is not JSON: ' + e.message); }
      // What is valid of it; one line on the page for each fault.
      let checked;
      try { checked = window.CandiSiteIndex.check(json); } catch (e) { (e.problems || []).forEach(fail); fail(e.message); throw e; }
      checked.problems.forEach(fail);
      const s = checked.site, d = s.data;
      site = s;
      origin = s.scene.origin;
      chunks = d.chunks;  // null where a chunk is bad
      groups = d.groups.map((g, gi) => {
        const box = { min: [Infinity, Infinity, Infinity], max: [-Infinity, -Infinity, -Infinity] };
        for (let c = g.chunks[0]; c < g.chunks[1]; ++c) for (let a = 0; a < 3; ++a) {
          box.min[a] = Math.min(box.min[a], chunks[c].min[a]); box.max[a] = Math.max(box.max[a], chunks[c].max[a]);
        }
        return { chunks: g.chunks, box, wanted: !g.dropped, dropped: g.dropped, rank: 0,
          pages: g.pages.map(({ bytes, points }) => ({ bytes, points, state: 'none', group: gi })) };
      });
      // The budget: the address's (a shared link's) when it is in the field's range, else the site's.
      const setBudget = (mb) => {
        budgetPoints = Math.floor(mb * 1e6 / 16);
        for (const gr of groups) for (const p of gr.pages) if (p.state === 'too large' && p.points <= budgetPoints) p.state = 'none';
      };
      const asked = new URLSearchParams(location.search).get('memory_mb');
      let mb = d.memory_mb;
      if (asked !== null) {
        const v = Number(asked);
        if (Number.isFinite(v) && v >= 16 && v <= 65536) mb = v;
        else fail('the address\'s memory_mb=' + asked.slice(0, 40) + ' is not in [16, 65536] MB: the site\'s ' + mb + ' MB is used');
      }
      setBudget(mb);
      $('memory-mb').value = mb;
      $('memory-mb').addEventListener('change', () => {
        const v = Number($('memory-mb').value);
        if (v >= 16 && v <= 65536) { setBudget(v); planOrder(); pump(); }
        else $('memory-mb').value = budgetPoints * 16 / 1e6;
      });
      return s.scene;
    }),
    update: (camera, settings) => {
      const before = state;
      state = { camera, settings };
      targets(camera.width, camera.height);
      makeProjector();
      restart();
      changedAt = performance.now();
      // The loading order follows the camera (at most every 250 ms) and the shown layers.
      if (!before || JSON.stringify(before.settings.layers) !== JSON.stringify(settings.layers)) { planOrder(); pump(); }
      else if (!replan) replan = setTimeout(() => { replan = null; planOrder(); pump(); }, 250);
    },
    pick,
    png,
    api: {
      webgl2: true,
      errors: () => errors.slice(),
      imageRgb,
      // settled: nothing more will be drawn; converged: and nothing is missing.
      progress: () => ({ drawn, L: state ? effectiveL() : 0, converged: !!state && drawn >= effectiveL() && !!convergedAt,
        settled: !!state && drawn >= effectiveL() && !inFlight, missing: groups.length ? missingPages() : '',
        firstImageAt, firstImageBytes, convergedAt, allLoadedAt, bytesReceived, pagesLoaded, heldPoints, budgetPoints,
        pagesFailed: groups.reduce((n, g) => n + g.pages.filter((p) => p.state === 'failed').length, 0) }),
      stats,
      siteRepeatLevel: () => site.data.repeat_level,
    },
  });
})();
