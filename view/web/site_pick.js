// candi publish: picking, on the client: the shown points under a pixel (shown layers, visible
// chunks, inside the clip planes, of the ensembles drawn), the nearest of each layer, and where
// the points are coloured by a field, the value a picked colour stands for.
import { ensembleSlices } from './site_index.js';
import { state, origin, effectiveL, projectLocal, chunkVisible, clipPlanes } from './site_view.js';
import { site, chunks } from './site_loader.js';

// Points packed coloured by a field: the value a picked colour stands for, as candi view's
// server reads it (FieldLegend::ValueOfColour): the middle of the values drawn in that colour
// and how far they reach either side; null for the grey (outside the range, or no value).
let colourRuns = null;  // colour -> [first, last] sample of the legend's scale
function valueOfColour(legend, colour) {
  if (Array.isArray(legend.classes)) {
    const c = legend.classes.find((k) => parseInt(k.colour.slice(1), 16) === colour);
    return { value: c ? c.code : null, value_half_width: 0 };
  }
  if (colour === parseInt(legend.grey.slice(1), 16)) return { value: null, value_half_width: 0 };
  if (!colourRuns) {
    colourRuns = new Map();
    for (const [c, first, last] of legend.runs) {
      const r = colourRuns.get(c);
      colourRuns.set(c, r ? [r[0], last] : [first, last]);
    }
  }
  const r = colourRuns.get(colour);
  const step = (legend.hi - legend.lo) / legend.steps;
  if (!r) {
    // A colour the samples skip lies, channel by channel, between the runs either side of one
    // step (FieldLegend::ValueOfColour).
    const ch = (c, s) => (c >> s) & 255;
    const between = (c, a, b, s) => (ch(a, s) <= ch(c, s) && ch(c, s) <= ch(b, s)) || (ch(b, s) <= ch(c, s) && ch(c, s) <= ch(a, s));
    for (let k = 0; k + 1 < legend.runs.length; ++k) {
      const a = legend.runs[k][0], b = legend.runs[k + 1][0];
      if (between(colour, a, b, 16) && between(colour, a, b, 8) && between(colour, a, b, 0)) {
        return { value: legend.lo + (legend.runs[k][2] + 0.5) * step, value_half_width: 0.5 * step };
      }
    }
    return { value: null, value_half_width: 0 };
  }
  return { value: legend.lo + 0.5 * (r[0] + r[1]) * step, value_half_width: 0.5 * (r[1] - r[0] + 2) * step };
}
// The backend's pick (controls.js): the nearest shown point of each layer under pixel (x, y).
export function pick(x, y) {
  const px = Math.floor(x), py = Math.floor(y), L = effectiveL(), f = state.settings.layers;
  const clip = clipPlanes();
  const best = new Map();  // layer -> {depth, point}
  const runs = [];
  for (let c = 0; c < chunks.length; ++c) {
    const ch = chunks[c];
    if (!ch) continue;
    const share = f ? f[ch.layer] : 1;
    if (!(share > 0) || !ch.segments.length || !chunkVisible(ch)) continue;
    runs.length = 0;
    for (let e = 0; e < L; ++e) ensembleSlices(ch, L, state.settings.seed, e, share, runs);
    const m = [(1 << ch.bits[0]) - 1, (1 << ch.bits[1]) - 1, (1 << ch.bits[2]) - 1];
    for (const s of ch.segments) {
      const w = s.page.words;
      for (let i = 0; i < runs.length; i += 2) {
        const b = Math.max(runs[i], s.begin), en = Math.min(runs[i + 1], s.end);
        for (let k = b; k < en; ++k) {
          const j = s.offset + k - s.begin, lo = w[2 * j], hi = w[2 * j + 1];
          // q: 40 bits; split without 32-bit overflow.
          const q = Math.floor(lo / 16777216) + hi * 256;
          const qx = q % (m[0] + 1), q1 = Math.floor(q / (m[0] + 1));
          const qy = q1 % (m[1] + 1), qz = Math.floor(q1 / (m[1] + 1)) % (m[2] + 1);
          const p = [ch.min[0] + qx * ch.step[0], ch.min[1] + qy * ch.step[1], ch.min[2] + qz * ch.step[2]];
          let kept = true;
          for (let t = 0; t < clip.count && kept; ++t) {
            const o = clip.out;
            if (o[4 * t] * p[0] + o[4 * t + 1] * p[1] + o[4 * t + 2] * p[2] < o[4 * t + 3]) kept = false;
          }
          if (!kept) continue;
          const uv = projectLocal(p);
          if (!uv || Math.floor(uv[0]) !== px || Math.floor(uv[1]) !== py) continue;
          const cur = best.get(ch.layer);
          if (!cur || uv[2] < cur.depth) {
            best.set(ch.layer, { layer: ch.layer, depth: uv[2], point: p.map((v, a) => v + origin[a]), colour: lo & 0xffffff });
          }
        }
      }
    }
  }
  const hits = [...best.values()].sort((a, b) => a.depth - b.depth);
  const legend = site.scene.legend;
  if (legend) for (const h of hits) Object.assign(h, valueOfColour(legend, h.colour));
  return Promise.resolve(hits.length ? { type: 'pick', hit: true, point: hits[0].point, depth: hits[0].depth, layer: hits[0].layer, hits }
    : { type: 'pick', hit: false, hits: [] });
}
