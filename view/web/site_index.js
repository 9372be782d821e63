// candi publish: the site's index (site.json, view/publish.h) checked before the page uses it,
// and the slices each ensemble draws (render/archive.cc's EnsembleSlices), which the check and
// the drawing share.
//
// check(json) -> {site, problems}: `site` is what is valid of the index, in the
// index's own shape (chunks as objects), `problems` one readable line per bad item (items of the
// same fault named together). What cannot be drawn is dropped with its line: a bad chunk, or a
// page count that does not match its chunks, drops its group (its pages hold the chunks' slices
// in order, so one wrong count misplaces the rest); a bad view, annotation, provenance entry or
// legend is left out; a bad setting takes its default. What makes the whole index unusable
// (the format, the repeat level, the layers, the origin, the seed, the chunks' field names)
// throws an Error saying what it is. Nothing here trusts a number it has not checked: counts
// are safe integers within what candi publish writes, coordinates finite, bits within 40.
const M64 = (1n << 64n) - 1n;
function mix64(z) {
  z = (z + 0x9e3779b97f4a7c15n) & M64;
  z = ((z ^ (z >> 30n)) * 0xbf58476d1ce4e5b9n) & M64;
  z = ((z ^ (z >> 27n)) * 0x94d049bb133111ebn) & M64;
  return z ^ (z >> 31n);
}
const streamKey = (seed, stream) => mix64(BigInt(seed) ^ mix64(BigInt(stream)));
const KEY_SLICE = {}, KEY_SHARE = {};
function keyFor(cache, seed, stream) {
  if (!(seed in cache)) cache[seed] = streamKey(seed, stream);
  return cache[seed];
}
// The offset r of a chunk's slices at (seed, L): ensemble e draws slice (e + r + j) mod L.
function sliceOffset(chunk, L, seed) {
  const id = seed + ':' + L;
  if (!(id in chunk.hashes)) {
    chunk.hashes[id] = Number(mix64(keyFor(KEY_SLICE, seed, 0x5EED511CEn) ^ BigInt(chunk.first)) % BigInt(L));
  }
  return chunk.hashes[id];
}
// The runs [begin, end) of a chunk that ensemble e draws (a share `fraction` of the points),
// pushed onto `out`.
export function ensembleSlices(chunk, L, seed, e, fraction, out) {
  const n = chunk.count;
  if (!(fraction > 0) || n === 0) return;
  const r = sliceOffset(chunk, L, seed);
  const bound = (s) => Math.floor(s * n / L);  // exact: s * n < 2^53
  for (let j = 0; j < Math.ceil(fraction) && j < L; ++j) {
    const s = (e + r + j) % L;
    const begin = bound(s), end = bound(s + 1);
    const share = Math.min(1, fraction - j);
    let take = end - begin;
    if (share < 1) {
      const x = share * (end - begin);
      const h = mix64(keyFor(KEY_SHARE, seed, 0xF4AC7n) ^ ((BigInt(chunk.first) * 131n + BigInt(s)) & M64));
      const u = Number(h >> 11n) * 2 ** -53;
      take = Math.floor(x) + ((x - Math.floor(x)) > u ? 1 : 0);
    }
    if (take > 0) out.push(begin, begin + take);
  }
}
// What candi publish writes at most (view/publish.h, render/archive.h).
const MAX_L = 1000;
const MAX_GROUP_POINTS = 2 ** 28;      // --group-points; a chunk above it is a group of its own
const MAX_CHUNK_POINTS = 2 ** 24;      // candi pack --chunk-points
const MAX_AXIS_BITS = 24, POSITION_BITS = 40;
const FAR = 1e9;                       // m: a local coordinate beyond this is no site's
const FIELDS = ['layer', 'count', 'first', 'group', 'min_x', 'min_y', 'min_z', 'max_x', 'max_y', 'max_z',
  'step_x', 'step_y', 'step_z', 'bits_x', 'bits_y', 'bits_z'];

const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
const finite = (v) => typeof v === 'number' && Number.isFinite(v);
const count = (v, max) => Number.isSafeInteger(v) && v >= 0 && v <= max;
const vec3 = (v) => Array.isArray(v) && v.length === 3 && v.every(finite);
const colourText = (v) => typeof v === 'string' && /^#[0-9a-fA-F]{6}$/.test(v);
function show(v) {
  let t;
  try { t = typeof v === 'number' ? String(v) : JSON.stringify(v); } catch (e) { t = String(v); }
  if (t === undefined) t = 'missing';
  return t.length > 40 ? t.slice(0, 37) + '…' : t;
}

// A camera as render/view_json.h writes it; null when it is not one.
function cameraProblem(c) {
  if (!isObject(c)) return 'not a camera';
  if (c.projection !== 'perspective' && c.projection !== 'orthographic') return 'projection ' + show(c.projection);
  for (const k of ['eye', 'target', 'up']) if (!vec3(c[k]) || c[k].some((x) => Math.abs(x) > 1e12)) return k + ' ' + show(c[k]);
  const d = [0, 1, 2].map((a) => c.target[a] - c.eye[a]);
  const len = Math.hypot(...d), up = Math.hypot(...c.up);
  if (!(len > 0) || !(up > 0)) return 'eye, target and up do not make a view';
  const cross = [d[1] * c.up[2] - d[2] * c.up[1], d[2] * c.up[0] - d[0] * c.up[2], d[0] * c.up[1] - d[1] * c.up[0]];
  if (!(Math.hypot(...cross) > 1e-9 * len * up)) return 'up is along the view direction';
  for (const k of ['width', 'height']) if (!(Number.isInteger(c[k]) && c[k] >= 1 && c[k] <= 16384)) return k + ' ' + show(c[k]);
  if (!(finite(c.fov_y_deg) && c.fov_y_deg > 0 && c.fov_y_deg < 180)) return 'fov_y_deg ' + show(c.fov_y_deg);
  if (!(finite(c.ortho_height) && c.ortho_height > 0)) return 'ortho_height ' + show(c.ortho_height);
  if (!(finite(c.near) && c.near > 0)) return 'near ' + show(c.near);
  return null;
}
// A view of the whole box from above, oblique (what candi view's first view does, roughly).
function defaultCamera(bounds) {
  const c = [0, 1, 2].map((a) => (bounds.min[a] + bounds.max[a]) / 2);
  const r = Math.max(1e-3, 0.5 * Math.hypot(...[0, 1, 2].map((a) => bounds.max[a] - bounds.min[a])));
  const d = r / Math.tan(20 * Math.PI / 180);
  const eye = [c[0] + 0.5 * d, c[1] - 0.6 * d, c[2] + 0.62 * d];
  return { projection: 'perspective', width: 1024, height: 768, eye, target: c, up: [0, 0, 1], fov_y_deg: 40,
    ortho_height: 2 * r, near: 1e-4 * d };
}

export function check(index) {
  const lines = new Map();  // fault -> the items that have it, in order
  const problem = (where, what) => {
    if (!lines.has(what)) lines.set(what, []);
    lines.get(what).push(where);
  };
  const fatal = (where, what) => { throw new Error('site.json: ' + where + ' ' + what + ': the site cannot be drawn'); };
  if (!isObject(index) || index.format !== 'candi site') fatal('', 'is not a candi site\'s index (format "candi site")');
  if (index.version !== 1) fatal('version', show(index.version) + ' is not 1 (this page reads version 1)');
  const data = index.data, scene = index.scene;
  if (!isObject(data)) fatal('data', 'is not an object');
  if (!isObject(scene)) fatal('scene', 'is not an object');

  // ---- what everything else depends on ----
  const L = data.repeat_level;
  if (!(Number.isInteger(L) && L >= 1 && L <= MAX_L)) fatal('data.repeat_level', show(L) + ' is not an integer in [1, ' + MAX_L + ']');
  const seed = data.seed;
  if (!Number.isSafeInteger(seed) || seed < 0) fatal('data.seed', show(seed) + ' is not an integer in [0, 2^53)');
  if (data.point_bytes !== 8) fatal('data.point_bytes', show(data.point_bytes) + ' is not 8');
  if (!Array.isArray(data.chunk_fields) || !FIELDS.every((f) => data.chunk_fields.includes(f))) {
    fatal('data.chunk_fields', 'does not name ' + FIELDS.join(', '));
  }
  if (!Array.isArray(data.chunks)) fatal('data.chunks', 'is not a list');
  if (!Array.isArray(data.groups)) fatal('data.groups', 'is not a list');
  if (!vec3(scene.origin) || scene.origin.some((x) => Math.abs(x) > 1e12)) fatal('scene.origin', show(scene.origin) + ' is not 3 finite numbers');
  if (!Array.isArray(scene.layers) || scene.layers.length === 0 || scene.layers.length > 4096) {
    fatal('scene.layers', 'is not a list of 1 to 4096 layers');
  }

  // ---- layers ----
  const layers = scene.layers.map((l, i) => {
    const where = 'scene.layers[' + i + ']';
    if (!isObject(l) || typeof l.name !== 'string') problem(where, 'has no name: named by its number');
    const o = isObject(l) ? l : {};
    return { name: typeof o.name === 'string' ? o.name : 'layer ' + (i + 1), kind: typeof o.kind === 'string' ? o.kind : '',
      points: count(o.points, 2 ** 53) ? o.points : 0, opacity: finite(o.opacity) ? o.opacity : 1, highlight: o.highlight === true };
  });

  // ---- chunks ----
  const F = Object.fromEntries(FIELDS.map((n) => [n, data.chunk_fields.indexOf(n)]));
  const chunks = data.chunks.map((a, c) => {
    const where = 'data.chunks[' + c + ']';
    if (!Array.isArray(a) || a.length < data.chunk_fields.length) { problem(where, 'is not a list of ' + data.chunk_fields.length + ' numbers: its group is not drawn'); return null; }
    const v = (n) => a[F[n]];
    const bad = (field, why) => { problem(where + '.' + field, show(v(field)) + ' ' + why + ': its group is not drawn'); return null; };
    if (!count(v('layer'), layers.length - 1)) return bad('layer', 'is not a layer of scene.layers');
    if (!count(v('count'), MAX_CHUNK_POINTS)) return bad('count', 'is not a point count');
    if (!count(v('first'), 2 ** 53 - 1)) return bad('first', 'is not a point number');
    if (!count(v('group'), data.groups.length - 1)) return bad('group', 'is not a group of data.groups');
    const min = [v('min_x'), v('min_y'), v('min_z')], max = [v('max_x'), v('max_y'), v('max_z')];
    const step = [v('step_x'), v('step_y'), v('step_z')], bits = [v('bits_x'), v('bits_y'), v('bits_z')];
    const axes = ['x', 'y', 'z'];
    for (let k = 0; k < 3; ++k) {
      if (!Number.isInteger(bits[k]) || bits[k] < 0 || bits[k] > MAX_AXIS_BITS) return bad('bits_' + axes[k], 'is not an integer in [0, ' + MAX_AXIS_BITS + ']');
    }
    const used = bits[0] + bits[1] + bits[2];
    if (used > POSITION_BITS) {
      problem(where + '.bits_x, bits_y, bits_z', show(bits) + ' make ' + used + ' bits, more than the 40 a point has: its group is not drawn');
      return null;
    }
    for (let k = 0; k < 3; ++k) {
      if (!(finite(min[k]) && Math.abs(min[k]) <= FAR)) return bad('min_' + axes[k], 'is not a finite coordinate within 10^9 m');
      if (!(finite(max[k]) && Math.abs(max[k]) <= FAR && max[k] >= min[k])) return bad('max_' + axes[k], 'is not a finite coordinate within 10^9 m, at least min_' + axes[k]);
      if (!(finite(step[k]) && step[k] >= 0 && (bits[k] === 0 || step[k] > 0))) return bad('step_' + axes[k], 'is not a finite step > 0');
      // The largest quantized value lands on the box (within rounding).
      const reach = (2 ** bits[k] - 1) * step[k];
      if (Math.abs(min[k] + reach - max[k]) > 1e-6 * Math.max(1, Math.abs(max[k]) + reach)) return bad('step_' + axes[k], 'does not span the chunk\'s box');
    }
    return { layer: v('layer'), count: v('count'), first: v('first'), group: v('group'), min, max, step, bits,
      segments: [], hashes: {}, visible: true };
  });

  // ---- groups and their pages ----
  let end = 0;
  const groups = data.groups.map((g, gi) => {
    const where = 'data.groups[' + gi + ']';
    const dropped = (what) => { problem(where, what + ': not drawn'); return { chunks: [0, 0], pages: [], dropped: true }; };
    if (!isObject(g)) return dropped('is not an object');
    const r = g.chunks;
    if (!Array.isArray(r) || r.length !== 2 || !count(r[0], chunks.length) || !count(r[1], chunks.length) || r[0] >= r[1]) {
      return dropped('chunks ' + show(r) + ' is not a range [first, end) of data.chunks');
    }
    if (r[0] < end) return dropped('chunks ' + show(r) + ' overlaps the group before');
    end = r[1];
    let points = 0;
    for (let c = r[0]; c < r[1]; ++c) {
      if (!chunks[c]) return dropped('holds a bad chunk (data.chunks[' + c + '])');
      if (chunks[c].group !== gi) return dropped('holds data.chunks[' + c + '], which names group ' + chunks[c].group);
      points += chunks[c].count;
    }
    if (r[1] - r[0] > 1 && points > MAX_GROUP_POINTS) return dropped('holds ' + points + ' points, more than a group holds (2^28)');
    if (!Array.isArray(g.pages)) return dropped('pages is not a list');
    if (g.pages.length !== L) return dropped('holds ' + g.pages.length + ' pages; data.repeat_level says ' + L);
    const pages = [], offsets = [];
    for (let c = r[0]; c < r[1]; ++c) offsets.push(sliceOffset(chunks[c], L, seed));
    for (let k = 0; k < L; ++k) {
      const p = g.pages[k];
      if (!Array.isArray(p) || p.length !== 2 || !count(p[0], 2 ** 40) || !count(p[1], 2 ** 53)) {
        return dropped('pages[' + k + '] ' + show(p) + ' is not [bytes, points]');
      }
      if (p[1] > MAX_GROUP_POINTS) return dropped('pages[' + k + '] claims ' + p[1] + ' points, more than a group holds (2^28)');
      let want = 0;
      for (let c = r[0], i = 0; c < r[1]; ++c, ++i) {
        const n = chunks[c].count, sl = (k + offsets[i]) % L;
        want += Math.floor((sl + 1) * n / L) - Math.floor(sl * n / L);
      }
      if (p[1] !== want) return dropped('pages[' + k + '] holds ' + p[1] + ' points; its chunks\' slices hold ' + want);
      // A gzip stream: at least its header and trailer, at most stored blocks of the 8 planes.
      const most = 8 * want + 5 * Math.ceil(8 * want / 16383) + 1024;
      if (p[0] < 18 || p[0] > most) return dropped('pages[' + k + '] is ' + p[0] + ' bytes, not a gzip stream of ' + want + ' points');
      pages.push({ bytes: p[0], points: p[1] });
    }
    return { chunks: [r[0], r[1]], pages, dropped: false };
  });
  const drawn = groups.filter((g) => !g.dropped);

  // ---- the scene ----
  const origin = scene.origin.slice();
  let bounds = scene.bounds;
  if (!(isObject(bounds) && vec3(bounds.min) && vec3(bounds.max) && bounds.min.every((x, a) => x <= bounds.max[a]))) {
    problem('scene.bounds', show(bounds) + ' is not a box: the chunks\' box is used');
    bounds = { min: [Infinity, Infinity, Infinity], max: [-Infinity, -Infinity, -Infinity] };
    for (const ch of chunks) if (ch) for (let a = 0; a < 3; ++a) {
      bounds.min[a] = Math.min(bounds.min[a], ch.min[a] + origin[a]);
      bounds.max[a] = Math.max(bounds.max[a], ch.max[a] + origin[a]);
    }
    if (!bounds.min.every(finite)) bounds = { min: origin.slice(), max: origin.slice() };
  } else {
    bounds = { min: bounds.min.slice(), max: bounds.max.slice() };
  }
  let firstView = scene.first_view;
  const why = cameraProblem(firstView);
  if (why) { problem('scene.first_view', 'is not a camera (' + why + '): a view of the whole is used'); firstView = defaultCamera(bounds); }
  let views = [];
  if (scene.views !== undefined && !Array.isArray(scene.views)) problem('scene.views', 'is not a list: no saved views');
  else if (Array.isArray(scene.views)) {
    scene.views.forEach((v, i) => {
      const bad = !isObject(v) ? 'not an object' : typeof v.name !== 'string' || !v.name ? 'no name' : cameraProblem(v.camera);
      if (bad) problem('scene.views[' + i + ']', 'is not a saved view (' + bad + '): left out');
      else views.push({ name: v.name, camera: v.camera, opaque: v.opaque === true });
    });
  }
  const s = isObject(scene.settings) ? scene.settings : {};
  if (!isObject(scene.settings)) problem('scene.settings', 'is not an object: the defaults are used');
  const setting = (key, ok, fallback) => {
    if (key in s && !ok(s[key])) problem('scene.settings.' + key, show(s[key]) + ' is not valid: ' + show(fallback) + ' is used');
    return key in s && ok(s[key]) ? s[key] : fallback;
  };
  const settings = {
    repeat_level: L,
    point_size: setting('point_size', (v) => finite(v) && v >= 1 && v <= 64, 1),
    background: setting('background', (v) => vec3(v) && v.every((x) => Number.isInteger(x) && x >= 0 && x <= 255), [0, 0, 0]).slice(),
    brightness: setting('brightness', (v) => v === 'auto' || v === 'none' || (finite(v) && v > 0 && v <= 100), 'auto'),
    opaque: setting('opaque', (v) => typeof v === 'boolean', false),
    seed,
    clip: setting('clip', (v) => Array.isArray(v) && v.length <= 16 &&
      v.every((p) => Array.isArray(p) && p.length === 6 && p.every(finite) && Math.hypot(p[3], p[4], p[5]) > 0), []).map((p) => p.slice()),
  };
  if ('seed' in s && s.seed !== seed) problem('scene.settings.seed', show(s.seed) + ' is not data.seed (' + seed + '): data.seed is used');
  if ('layers' in s && s.layers !== null) {
    if (Array.isArray(s.layers) && s.layers.length === layers.length && s.layers.every((f) => finite(f) && f >= 0 && f <= 16)) settings.layers = s.layers.slice();
    else problem('scene.settings.layers', show(s.layers) + ' is not a share in [0, 16] for each layer: all 1');
  }

  // Optional parts: what is valid is kept, the rest named.
  let provenance;
  if (scene.provenance !== undefined) {
    const p = scene.provenance;
    if (!isObject(p)) problem('scene.provenance', 'is not an object: left out');
    else {
      provenance = {};
      if (p.crs !== undefined && p.crs !== null) {
        if (isObject(p.crs) || typeof p.crs === 'string') provenance.crs = p.crs;
        else problem('scene.provenance.crs', show(p.crs) + ' is not a CRS: left out');
      }
      if (p.licence !== undefined) {
        if (typeof p.licence === 'string') provenance.licence = p.licence;
        else problem('scene.provenance.licence', show(p.licence) + ' is not text: left out');
      }
      provenance.layers = [];
      if (p.layers !== undefined && !Array.isArray(p.layers)) problem('scene.provenance.layers', 'is not a list: left out');
      (Array.isArray(p.layers) ? p.layers : []).forEach((l, i) => {
        if (!isObject(l) || typeof l.name !== 'string') { problem('scene.provenance.layers[' + i + ']', 'is not a layer\'s provenance (no name): left out'); return; }
        const e = { name: l.name };
        if (typeof l.kind === 'string') e.kind = l.kind;
        if (typeof l.method === 'string') e.method = l.method;
        if (typeof l.scanned === 'boolean') e.scanned = l.scanned;
        e.sources = (Array.isArray(l.sources) ? l.sources : []).filter((x) => isObject(x) && typeof x.file === 'string').map((x) => ({ file: x.file }));
        if (Array.isArray(l.sources) && e.sources.length !== l.sources.length) {
          problem('scene.provenance.layers[' + i + '].sources', 'holds entries without a file name: left out');
        }
        provenance.layers.push(e);
      });
      provenance.annotations = [];
      if (p.annotations !== undefined && !Array.isArray(p.annotations)) problem('scene.provenance.annotations', 'is not a list: left out');
      (Array.isArray(p.annotations) ? p.annotations : []).forEach((a, i) => {
        const bad = !isObject(a) ? 'not an object' : typeof a.title !== 'string' ? 'no title' : !vec3(a.position) ? 'no position' :
          a.text !== undefined && typeof a.text !== 'string' ? 'its text is not text' :
            a.view !== undefined && typeof a.view !== 'string' && cameraProblem(Object.assign({ width: 1, height: 1, projection: 'perspective', fov_y_deg: 40, ortho_height: 1, near: 1 }, a.view)) ? 'its view is not a camera' : null;
        if (bad) { problem('scene.provenance.annotations[' + i + ']', 'is not an annotation (' + bad + '): left out'); return; }
        const e = { title: a.title, position: a.position.slice() };
        if (typeof a.text === 'string') e.text = a.text;
        if (a.view !== undefined) e.view = a.view;
        provenance.annotations.push(e);
      });
    }
  }
  let legend;
  if (scene.legend !== undefined && scene.legend !== null) {
    const l = scene.legend;
    const bad = !isObject(l) ? 'not an object' : typeof l.field !== 'string' ? 'field' : !colourText(l.grey) ? 'grey' :
      !count(l.outside, 2 ** 53) ? 'outside' : !count(l.undefined, 2 ** 53) ? 'the count without a value' :
        Array.isArray(l.classes) ? (l.classes.every((c) => isObject(c) && Number.isInteger(c.code) && typeof c.name === 'string' && colourText(c.colour)) ? null : 'classes')
          : !(finite(l.lo) && finite(l.hi) && l.lo < l.hi) ? 'lo, hi'
            : !(Number.isInteger(l.steps) && l.steps >= 1 && l.steps <= 1e6) ? 'steps'
              : !(Array.isArray(l.stops) && l.stops.length >= 2 && l.stops.every(colourText)) ? 'stops'
                : !(Array.isArray(l.runs) && l.runs.every((r) => Array.isArray(r) && r.length === 3 && count(r[0], 0xffffff) &&
                  count(r[1], l.steps) && count(r[2], l.steps) && r[1] <= r[2])) ? 'runs' : null;
    if (bad) problem('scene.legend', 'is not a field\'s legend (' + bad + '): left out; picks give no values');
    else legend = l;
  }

  let points = 0;
  for (const g of drawn) for (let c = g.chunks[0]; c < g.chunks[1]; ++c) points += chunks[c].count;
  const memoryMb = count(data.memory_mb, 65536) && data.memory_mb >= 16 ? data.memory_mb : 128;
  if (memoryMb !== data.memory_mb) problem('data.memory_mb', show(data.memory_mb) + ' is not in [16, 65536]: 128 is used');

  const site = {
    format: index.format, version: 1,
    scene: { title: typeof scene.title === 'string' ? scene.title : 'untitled', kind: typeof scene.kind === 'string' ? scene.kind : '',
      points, chunks: chunks.length, origin, bounds, layers, views, first_view: firstView, settings, provenance, legend },
    data: { repeat_level: L, seed, memory_mb: memoryMb, chunks, groups },
  };
  const problems = [];
  for (const [what, where] of lines) {
    const named = where.length <= 4 ? where.join(', ') : where.slice(0, 3).join(', ') + ' … ' + where[where.length - 1] + ' (' + where.length + ' in all)';
    problems.push('site.json: ' + named + ' ' + what);
  }
  if (!drawn.length) {
    const e = new Error('site.json: none of its ' + groups.length + ' groups can be drawn (' + (groups.length ? 'named above' : 'data.groups is empty') +
      '): the site cannot be drawn');
    e.problems = problems;
    throw e;
  }
  return { site, problems };
}

