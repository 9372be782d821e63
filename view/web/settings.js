// The "View" and "Rendering" controls: the settings (L, point size, background, opacity,
// brightness) read from and shown in their fields, the projection, the camera reset to the
// first or a saved view, and the view and the converged image saved as files.
import { $, download } from './dom.js';
import { add, sub, mul, norm, unit } from './vec.js';
import { canvas, backend, scene, camera, settings, setCamera, changed, clone } from './page.js';
import { fitCanvas } from './camera.js';
import { viewJson } from './sharing.js';

const hex = (c) => '#' + c.map((v) => v.toString(16).padStart(2, '0')).join('');
const rgb = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
export function syncControls() {
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
export function readSettings() {
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
export function onProjection() {
  const p = $('projection').value;
  if (p === camera.projection) return;
  // Keep what is seen at the target: the ortho height equals the perspective view's height there.
  const d = norm(sub(camera.target, camera.eye));
  if (p === 'orthographic') camera.ortho_height = 2 * d * Math.tan(camera.fov_y_deg * Math.PI / 360);
  else camera.eye = add(camera.target, mul(unit(sub(camera.eye, camera.target)), camera.ortho_height / (2 * Math.tan(camera.fov_y_deg * Math.PI / 360))));
  camera.projection = p;
  changed();
}
// The camera of `view` (the scene's first view when none), shown in the controls.
export function resetView(view) {
  setCamera(clone(view || scene.first_view));
  fitCanvas(true);
  syncControls();
  changed();
}
// The scene's saved views in the "Saved views" list.
export function listViews(views) {
  for (const v of views) { const o = document.createElement('option'); o.value = v.name; o.textContent = v.name; $('views').appendChild(o); }
}
export function wireSettings() {
  ['repeat-level', 'point-size', 'background', 'opaque', 'brightness', 'gain'].forEach((id) => $(id).addEventListener('input', readSettings));
  $('projection').addEventListener('change', onProjection);
  $('reset').addEventListener('click', () => resetView());
  $('views').addEventListener('change', () => {
    const v = scene.views.find((x) => x.name === $('views').value);
    resetView(v ? v.camera : null);
    if (v) { settings.opaque = !!v.opaque; syncControls(); }
  });
  $('save-view').addEventListener('click', () => download('view.json', new Blob([viewJson()], { type: 'application/json' })));
  $('save-png').addEventListener('click', () => backend.png().then((blob) => {
    if (blob) download(scene.title + '.png', blob);
    else $('status').textContent = 'the image has not converged yet: wait for ' + settings.repeat_level + ' ensembles';
  }));
}
