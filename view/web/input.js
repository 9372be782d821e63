// The canvas's input: drag to orbit (right, middle or shift-drag: pan), two-finger pinch, wheel
// zoom, double-click to fly to the point, a click to measure (measure mode) or to open an
// annotation's marker, the keys of the Help box, and the window's resizing.
import { $ } from './dom.js';
import { canvas, backend, camera } from './page.js';
import { orbit, pan, zoom, flyTo, fitCanvas } from './camera.js';
import { readSettings, onProjection, resetView } from './settings.js';
import { measureAt } from './measure.js';
import { annotations, openAnnotationsAt } from './annotations.js';

function pixelOf(e) {
  const rect = canvas.getBoundingClientRect();
  return [(e.clientX - rect.left) * camera.width / rect.width, (e.clientY - rect.top) * camera.height / rect.height];
}
export function wireInput() {
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
    const [x, y] = pixelOf(e);
    backend.pick(x, y).then((m) => { if (m.hit) flyTo(m.point); });
  });
  // A click: a press and release of the left button that did not move. In measure mode it picks
  // a point; otherwise, on a marker, it opens that annotation.
  let press = null;
  canvas.addEventListener('pointerdown', (e) => { press = { x: e.clientX, y: e.clientY, button: e.button }; });
  const clicked = (e) => press && press.button === 0 && Math.hypot(e.clientX - press.x, e.clientY - press.y) <= 3;
  canvas.addEventListener('pointerup', (e) => {
    if (!$('measure').checked || !clicked(e)) return;
    const [x, y] = pixelOf(e);
    measureAt(x, y);
  });
  canvas.addEventListener('pointerup', (e) => {
    if ($('measure').checked || !annotations.length || !clicked(e)) return;
    const [x, y] = pixelOf(e);
    openAnnotationsAt(x, y);
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
}
