// Measuring: points picked on the image (shown points only, in survey coordinates), the
// distances between consecutive ones, their table and their export as CSV and JSON.
import { $, download } from './dom.js';
import { sub, norm } from './vec.js';
import { backend, scene } from './page.js';

export const measurements = [];  // { hits: the pick's hits (nearest first), index: the one used }
export const at = (m) => m.hits[m.index];
export const layerName = (i) => (scene.layers[i] ? scene.layers[i].name : 'layer ' + i);
export let shownCount = 0;  // how many times the table was drawn (the overlay follows it)
export function measureAt(x, y) {
  return backend.pick(x, y).then((m) => {
    if (!m.hit) { $('status').textContent = 'nothing shown under that pixel'; return null; }
    const last = measurements[measurements.length - 1];
    if (last && at(last).point.every((v, k) => v === m.hits[0].point[k])) return last;  // a double click
    measurements.push({ hits: m.hits, index: 0 });
    showMeasurements();
    return measurements[measurements.length - 1];
  });
}
// Between consecutive points: distance, horizontal distance, height difference.
export function segments() {
  const out = [];
  for (let i = 1; i < measurements.length; ++i) {
    const a = at(measurements[i - 1]).point, b = at(measurements[i]).point, d = sub(b, a);
    out.push({ from: i, to: i + 1, distance: norm(d), horizontal: Math.hypot(d[0], d[1]), dz: d[2] });
  }
  return out;
}
// Measurement i takes the next shown layer's point under the same pixel.
export function stepBehind(i) {
  const m = measurements[i];
  m.index = (m.index + 1) % m.hits.length;
  showMeasurements();
}
function showMeasurements() {
  const body = $('measurements').querySelector('tbody');
  body.textContent = '';
  measurements.forEach((m, i) => {
    const tr = document.createElement('tr');
    const h = at(m);
    // Points coloured by a field: its value, read back from the point's colour by the server.
    const field = scene.legend && 'value' in h ? ' · ' + scene.legend.field + ' ' + (h.value === null ? 'grey (outside or none)'
      : Number(h.value).toPrecision(4) + ' ± ' + Number(h.value_half_width).toPrecision(1)) : '';
    const cells = [String(i + 1), layerName(h.layer) + (m.hits.length > 1 ? ' (' + (m.index + 1) + '/' + m.hits.length + ')' : '') + field,
      h.point[0].toFixed(3), h.point[1].toFixed(3), h.point[2].toFixed(3)];
    for (const c of cells) { const td = document.createElement('td'); td.textContent = c; tr.appendChild(td); }
    const td = document.createElement('td');
    if (m.hits.length > 1) {
      const behind = document.createElement('button');
      behind.textContent = 'behind';
      behind.title = 'the next shown layer\'s point under the same pixel';
      behind.addEventListener('click', () => { m.index = (m.index + 1) % m.hits.length; showMeasurements(); });
      td.appendChild(behind);
    }
    const remove = document.createElement('button');
    remove.textContent = '×';
    remove.addEventListener('click', () => { measurements.splice(i, 1); showMeasurements(); });
    td.appendChild(remove);
    tr.appendChild(td);
    body.appendChild(tr);
  });
  const lines = segments().map((g) => g.from + '→' + g.to + ': ' + g.distance.toFixed(3) + ' m · horizontal ' +
    g.horizontal.toFixed(3) + ' · Δz ' + (g.dz >= 0 ? '+' : '') + g.dz.toFixed(3));
  const total = segments().reduce((t, g) => t + g.distance, 0);
  $('measure-summary').textContent = lines.join('\n') + (lines.length > 1 ? '\ntotal ' + total.toFixed(3) + ' m' : '');
  $('measure-summary').style.whiteSpace = 'pre-line';
  shownCount += 1;
}
export function measurementsCsv() {
  let out = 'point,layer,x,y,z,distance_m,horizontal_m,dz_m\n';
  const g = segments();
  measurements.forEach((m, i) => {
    const h = at(m), s = i > 0 ? g[i - 1] : null;
    out += [i + 1, JSON.stringify(layerName(h.layer)), ...h.point.map((v) => v.toFixed(4)),
      s ? s.distance.toFixed(4) : '', s ? s.horizontal.toFixed(4) : '', s ? s.dz.toFixed(4) : ''].join(',') + '\n';
  });
  return out;
}
function measurementsJson() {
  return JSON.stringify({ frame: 'world (survey) coordinates, metres', archive: scene.title,
    points: measurements.map((m, i) => ({ index: i + 1, layer: layerName(at(m).layer), point: at(m).point })),
    segments: segments() }, null, 2) + '\n';
}
export function wireMeasuring() {
  $('measure-csv').addEventListener('click', () => download('measurements.csv', new Blob([measurementsCsv()], { type: 'text/csv' })));
  $('measure-json').addEventListener('click', () => download('measurements.json', new Blob([measurementsJson()], { type: 'application/json' })));
  $('measure-clear').addEventListener('click', () => { measurements.length = 0; showMeasurements(); });
}
