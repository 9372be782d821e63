// The overlay over the image: the annotations' markers and the measured points with the lines
// between them, projected as the server projects; redrawn when the camera, the measurements or
// the annotations change.
import { $ } from './dom.js';
import { camera } from './page.js';
import { project } from './camera.js';
import { measurements, at, shownCount } from './measure.js';
import { annotations } from './annotations.js';

const overlay = $('overlay'), octx = overlay.getContext('2d');
let overlayKey = '';
export function drawOverlay() {
  if (camera) {
    const key = JSON.stringify([camera, measurements.map((m) => m.index), measurements.length, annotations.length, shownCount]);
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
