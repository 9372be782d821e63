// The camera's movements (orbit, pan, zoom, the flight to a point), the canvas's size, and the
// projection of a world point to a pixel as the server projects it. Each change marks the view
// changed; the page sends it on the next animation frame.
import { add, sub, mul, dot, cross, norm, unit } from './vec.js';
import { canvas, camera, changed } from './page.js';

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
export function orbit(dx, dy) {
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
export function pan(dx, dy) {
  const b = basis(), m = metresPerPixel();
  const shift = add(mul(b.r, -dx * m), mul(b.u, dy * m));
  camera.eye = add(camera.eye, shift);
  camera.target = add(camera.target, shift);
  changed();
}
export function zoom(factor) {
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
export function flyTo(point) {
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
export function fitCanvas(force) {
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
// A world point's pixel [x, y], or null behind the near plane.
export function project(p) {
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
