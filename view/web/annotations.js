// The scene's annotations (its labelled points): the list in the "Annotations" box, a marker on
// the overlay for each; a click on either flies to its view (a scene view's name, an inline
// camera, or its position).
import { $ } from './dom.js';
import { vec3 } from './vec.js';
import { scene, changed } from './page.js';
import { flyTo, fitCanvas, project } from './camera.js';
import { resetView, syncControls } from './settings.js';
import { applyShared } from './sharing.js';

export let annotations = [];
export function openAnnotation(i) {
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
// Opens every annotation whose marker is within 10 pixels of (x, y).
export function openAnnotationsAt(x, y) {
  annotations.forEach((a, i) => { const q = project(a.position); if (q && Math.hypot(q[0] - x, q[1] - y) < 10) openAnnotation(i); });
}
export function buildAnnotations() {
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
}
