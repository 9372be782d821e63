// Clipping and sections: the clip box (survey coordinates), the section's slab (across the view,
// through the last two measured points, or level at the last one) shown alone looking along its
// normal, and its export by the server (candi section's DXF, SVG, CSV and PNG). The clip planes
// go to the backend in settings.clip, after those the page was started with.
import { $, blobLink } from './dom.js';
import { add, sub, mul, cross, norm, unit } from './vec.js';
import { backend, camera, settings, setCamera, changed, clone } from './page.js';
import { fitCanvas } from './camera.js';
import { syncControls } from './settings.js';
import { measurements, at } from './measure.js';

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
    setCamera(beforeSection);
    beforeSection = null;
    fitCanvas(true);
    syncControls();
  }
  updateClip();
}
export let lastSection = null;
export function exportSection(s) {
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
// The scene's clipping (kept under the page's own) and the clip box's fields at its bounds.
export function startClipping(scene) {
  baseClip = settings.clip || [];
  settings.clip = baseClip.slice();
  boxIds.forEach((id, k) => { $(id).value = (k < 3 ? scene.bounds.min[k] : scene.bounds.max[k - 3]).toFixed(3); });
}
export function wireSections() {
  $('section-export').addEventListener('click', () => {
    try { exportSection(sectionPlane()); } catch (e) { $('section-summary').textContent = e.message; }
  });
  $('clip-box').addEventListener('input', updateClip);
  boxIds.forEach((id) => $(id).addEventListener('change', updateClip));
  $('section-show').addEventListener('input', onSectionShow);
  ['section-plane', 'section-thickness'].forEach((id) => $(id).addEventListener('change', () => { if ($('section-show').checked) updateClip(); }));
}
