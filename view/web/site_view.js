// candi publish: the view being drawn (the camera and settings the page last sent) in the site's
// local frame (site.json's origin subtracted, so float32 keeps the points' precision): its
// projector, a box's visibility, the clip planes, and L as drawn (1 when opaque).
import { sub, dot, cross } from './vec.js';
import { W, H } from './site_gl.js';

export let state = null;       // {camera, settings}
export let origin = [0, 0, 0];
let bounds = null;             // the archive's, in world coordinates
export let proj = null;
// Unit length by division (the projector has always normalised so; vec.js's unit multiplies).
const norm3 = (a) => { const n = Math.sqrt(dot(a, a)); return [a[0] / n, a[1] / n, a[2] / n]; };

export function setFrame(o, b) { origin = o; bounds = b; }
export const effectiveL = () => (state.settings.opaque ? 1 : state.settings.repeat_level);
// The view to draw, and its projector.
export function setView(camera, settings) {
  state = { camera, settings };
  makeProjector();
}
function makeProjector() {
  const c = state.camera;
  const eye = c.eye.map((x, a) => x - origin[a]), target = c.target.map((x, a) => x - origin[a]);
  const f = norm3(sub(target, eye));
  const r = norm3(cross(f, c.up));
  const u = cross(f, r);  // camera y (down)
  const R = [r, u, f];
  const focal = c.projection === 'orthographic' ? c.height / c.ortho_height : 0.5 * c.height / Math.tan(c.fov_y_deg * Math.PI / 360);
  proj = { R, eye, focal, cx: 0.5 * c.width, cy: 0.5 * c.height, perspective: c.projection !== 'orthographic', near: c.near };
  // Depths for the depth buffer: the archive's bounds along the view axis.
  const b = bounds;
  let zmin = Infinity, zmax = -Infinity;
  for (let i = 0; i < 8; ++i) {
    const p = [0, 1, 2].map((a) => ((i >> a) & 1 ? b.max[a] : b.min[a]) - origin[a] - eye[a]);
    const z = dot(f, p);
    zmin = Math.min(zmin, z); zmax = Math.max(zmax, z);
  }
  const pad = 1e-3 * (zmax - zmin) + 1e-6;
  proj.zmin = Math.min(zmin - pad, proj.perspective ? c.near : zmin - pad);
  proj.zmax = zmax + pad;
}
// A local point's pixel and depth [x, y, z], or null behind the near plane.
export function projectLocal(p) {
  const d = sub(p, proj.eye), c = proj.R.map((row) => dot(row, d));
  if (proj.perspective && c[2] <= proj.near) return null;
  const s = proj.perspective ? proj.focal / c[2] : proj.focal;
  return [proj.cx + s * c[0], proj.cy + s * c[1], c[2]];
}
// Whether any of the local box [min, max] may be in the image (with a margin of m pixels).
export function boxInView(min, max, m) {
  let left = 0, right = 0, top = 0, bottom = 0, behind = 0;
  for (let i = 0; i < 8; ++i) {
    const q = projectLocal([i & 1 ? max[0] : min[0], i & 2 ? max[1] : min[1], i & 4 ? max[2] : min[2]]);
    if (!q) { behind++; continue; }
    if (q[0] < -m) left++; if (q[0] >= W + m) right++; if (q[1] < -m) top++; if (q[1] >= H + m) bottom++;
  }
  if (behind === 8) return false;
  if (behind > 0) return true;
  return !(left === 8 || right === 8 || top === 8 || bottom === 8);
}
// A chunk whose points, a point's size around them, may be in the image.
export const chunkVisible = (ch) => boxInView(ch.min, ch.max, state.settings.point_size + 1);
// The clip planes in the local frame, unit normals: (n, n . p) for each, at most 16.
export function clipPlanes() {
  const out = new Float32Array(64);
  const planes = (state.settings.clip || []).slice(0, 16);
  planes.forEach((p, i) => {
    const n = [p[3], p[4], p[5]], len = Math.hypot(...n);
    const pt = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
    out.set([n[0] / len, n[1] / len, n[2] / len, dot(n, pt) / len], 4 * i);
  });
  return { out, count: planes.length };
}
