// What the page says about the archive: the title (its points, or the preview's share while the
// rest packs), "About this archive" (the CRS, the licence, each layer measured or reconstructed,
// its method and sources) and the legend of a colouring by a field.
import { $ } from './dom.js';
import { scene } from './page.js';

export function showTitle() {
  const p = scene.preview;
  $('title').textContent = scene.title + ' · ' + (p ? 'preview: 1 point in ' + p.every + ' of ' +
    p.points.toLocaleString() + ' points, the rest packing' : scene.points.toLocaleString() + ' points');
}
function describeCrs(c) {
  if (!c) return 'none stated (local coordinates)';
  return c.label || c.definition || c.to || JSON.stringify(c);
}
export function buildProvenance() {
  const p = scene.provenance || {};
  const box = $('provenance');
  box.textContent = '';
  const line = (text, cls) => { const d = document.createElement('div'); d.textContent = text; if (cls) d.className = cls; box.appendChild(d); return d; };
  line('CRS: ' + describeCrs(p.crs));
  if (typeof p.licence === 'string') line('Licence: ' + p.licence);
  const layers = Array.isArray(p.layers) ? p.layers : [];
  if (!layers.length) line('No provenance: a render archive or point files (a build directory records it).', 'hint');
  for (const l of layers) {
    const d = line('', 'layer');
    const head = document.createElement('div');
    head.className = 'name';
    head.textContent = l.name + ' · ' + (l.scanned === true ? 'measured' : l.scanned === false ? 'reconstructed' : 'unknown') + (l.kind ? ' (' + l.kind + ')' : '');
    d.appendChild(head);
    if (l.method) { const m = document.createElement('div'); m.className = 'hint'; m.textContent = l.method; d.appendChild(m); }
    if (Array.isArray(l.sources) && l.sources.length) {
      const m = document.createElement('div');
      m.className = 'hint';
      m.textContent = 'from ' + l.sources.slice(0, 6).map((x) => x.file).join(', ') + (l.sources.length > 6 ? ' and ' + (l.sources.length - 6) + ' more' : '');
      d.appendChild(m);
    }
  }
}
// The colouring by a field (candi view FILE --colour-by): its scale, range and grey's counts.
export function buildLegend() {
  const l = scene.legend;
  const box = $('legend');
  box.textContent = '';
  box.hidden = !l;
  if (!l) return;
  const div = (text, cls) => { const d = document.createElement('div'); d.textContent = text; if (cls) d.className = cls; box.appendChild(d); return d; };
  const swatch = (colour) => { const b = document.createElement('span'); b.className = 'swatch'; b.style.background = colour; return b; };
  // 3 significant digits without trailing zeros after the point (100 stays 100; 0.0100 is 0.01).
  const num = (v) => {
    const t = Number(v).toPrecision(3);
    if (t.includes('e')) return t.replace(/\.?0+e/, 'e');
    return t.includes('.') ? t.replace(/\.?0+$/, '') : t;
  };
  div(l.field, 'name');
  if (Array.isArray(l.classes)) {
    for (const c of l.classes) { const d = div(' ' + c.code + ' ' + c.name); d.prepend(swatch(c.colour)); }
  } else {
    const bar = div('', 'scale');
    bar.style.background = 'linear-gradient(to right, ' + l.stops.join(', ') + ')';
    const ticks = div('', 'ticks');
    const mid = l.scale === 'diverging' && l.lo === -l.hi ? 0 : (l.lo + l.hi) / 2;
    for (const v of [l.lo, mid, l.hi]) { const t = document.createElement('span'); t.textContent = num(v); ticks.appendChild(t); }
  }
  const grey = [];
  if (!Array.isArray(l.classes)) grey.push(l.outside.toLocaleString() + ' outside');
  if (l.undefined > 0) grey.push(l.undefined.toLocaleString() + ' without a value');
  if (grey.length) { const d = div(' ' + grey.join(', '), 'hint'); d.prepend(swatch(l.grey)); }
}
