// candi publish: SPBR with WebGL2, as candi render's (render/spbr.h). Per ensemble, that
// ensemble's points with a depth test into an 8-bit image; the ensembles' colours and hits are
// summed in a float32 target (sums of up to L 8-bit values are exact); the shown image is
// (gain * sum + (k - hits) * background) / k, rounded. Here: the context, the programs, the
// targets, the points' vertex buffers, an ensemble drawn and added, the image shown (auto
// brightness: render/spbr.cc's AutoBrightnessGain) and read back.
import { canvas } from './page.js';
import { sub, dot } from './vec.js';

export const gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: false, preserveDrawingBuffer: true,
  premultipliedAlpha: false });
const floatTargets = gl && gl.getExtension('EXT_color_buffer_float');
// Why this browser cannot draw the site, or '' when it can.
export const glProblem = !gl ? 'this browser gives no WebGL2' : !floatTargets ? 'this browser cannot render to float32 targets (EXT_color_buffer_float)' : '';

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

let pointProgram = null, addProgram = null, showProgram = null, pu = null, au = null, su = null, vao = null;
if (!glProblem) {
  pointProgram = compile(pointVs, pointFs); addProgram = compile(quadVs, addFs); showProgram = compile(quadVs, showFs);
  const uniforms = (p, names) => Object.fromEntries(names.map((n) => [n, gl.getUniformLocation(p, n)]));
  pu = uniforms(pointProgram, ['bits', 'A', 'b', 'chunkMin', 'step', 'focal', 'cx', 'cy', 'near', 'width', 'height', 'zmin', 'zmax',
    'pointSize', 'perspective', 'planes', 'clip']);
  au = uniforms(addProgram, ['acc', 'ens']);
  su = uniforms(showProgram, ['acc', 'k', 'gain', 'background']);
  vao = gl.createVertexArray();
}

// ---- targets -----------------------------------------------------------------------------
export let W = 0, H = 0;
let ensFbo, ensTex, depthRb, accTex = [], accFbo = [], accIndex = 0;
function texture(internal, format, type) {
  const t = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, t);
  gl.texStorage2D(gl.TEXTURE_2D, 1, internal, W, H);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  return t;
}
// The targets at the image's size w x h (made anew when it changes).
export function targets(w, h) {
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

// ---- the points' buffers ---------------------------------------------------------------------
// A page's points (8-byte words as (lo, hi)) as a vertex buffer.
export function upload(words) {
  const vbo = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
  gl.bufferData(gl.ARRAY_BUFFER, words, gl.STATIC_DRAW);
  return vbo;
}
export function release(vbo) { gl.deleteBuffer(vbo); }

// ---- drawing -------------------------------------------------------------------------------
let firstGrey = null;    // the first ensemble's grey histogram (auto brightness)
export let gain = 1;
export const stats = { images: 0, ensemblesDrawn: 0, pointsDrawn: 0 };
// The image starts again: its next first ensemble gives auto brightness's histogram.
export function forgetGrey() { firstGrey = null; }
export function clearSums() {
  gl.bindFramebuffer(gl.FRAMEBUFFER, accFbo[accIndex]);
  gl.clearColor(0, 0, 0, 0);
  gl.clear(gl.COLOR_BUFFER_BIT);
}
// Ensemble e: `ranges` holds [chunk, page, first, count] of its points (a page's vertex buffer),
// drawn with the projector `proj` (site_view.js) and the clip planes `clip`, then added to the
// sums.
export function drawEnsemble(e, ranges, chunks, proj, clip, settings) {
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
  gl.uniform1f(pu.pointSize, Math.round(settings.point_size));
  gl.uniform1i(pu.perspective, proj.perspective ? 1 : 0);
  gl.uniform1i(pu.planes, clip.count);
  gl.uniform4fv(pu.clip, clip.out);
  let chunk = -1, vbo = null;
  for (let i = 0; i < ranges.length; i += 4) {
    const c = ranges[i], page = ranges[i + 1];
    if (c !== chunk) {
      chunk = c;
      const ch = chunks[c];
      const b = proj.R.map((row) => dot(row, sub(ch.min, proj.eye)));
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
  if (e === 0 && settings.brightness === 'auto') firstGrey = greyHistogram();
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
// The image of k ensembles of L on the canvas.
export function show(k, L, settings) {
  const b = settings.brightness;
  gain = b === 'auto' ? (k === L || k === 1 || k % 8 === 0 ? autoGain(k) : gain) : b === 'none' ? 1 : Number(b);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  gl.viewport(0, 0, W, H);
  gl.useProgram(showProgram);
  gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, accTex[accIndex]);
  gl.uniform1i(su.acc, 0);
  gl.uniform1f(su.k, k);
  gl.uniform1f(su.gain, gain);
  gl.uniform3fv(su.background, settings.background);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  stats.images += 1;
}
// The shown image, rows top first, RGB (tests compare it with candi render's PNG).
export function imageRgb() {
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
