// candi publish: the page's backend that renders in the visitor's browser, and the site's entry
// module (candi publish writes it into index.html in place of viewer.js). SPBR with WebGL2
// (site_gl.js) of the view the page sends (site_view.js), over the pages the loader brings in
// ensemble order within a memory budget (site_loader.js); picking on the client (site_pick.js).
// Here: the schedule of the ensembles (which points each draws, how many a frame, when the image
// starts again), the status line, and the backend handed to the page (controls.js).
import { $ } from './dom.js';
import { canvas } from './page.js';
import { startPage } from './controls.js';
import { ensembleSlices } from './site_index.js';
import { gl, glProblem, targets, clearSums, drawEnsemble, show, forgetGrey, imageRgb, gain, stats } from './site_gl.js';
import { state, proj, setView, effectiveL, chunkVisible, clipPlanes } from './site_view.js';
import { errors, fail, hooks, site, chunks, groups, loadSite, planOrder, pump, ensembleReady, missingPages, budgetReached,
  progressText, budgetPoints, heldPoints, inFlight, bytesReceived, pagesLoaded, allLoadedAt } from './site_loader.js';
import { pick } from './site_pick.js';

let drawn = 0;           // ensembles accumulated
let changedAt = 0, firstImageAt = null, firstImageBytes = null, convergedAt = null;
function restart() { drawn = 0; forgetGrey(); convergedAt = null; }
hooks.evicted = restart;
hooks.arrived = (k) => {
  // A page of ensemble k changes the image only if that ensemble was drawn (at the site's L, f <= 1).
  const L = effectiveL();
  const aligned = L === site.data.repeat_level && (state.settings.layers || []).every((f) => f <= 1);
  if (!aligned || k < drawn) restart();
};

// The draw ranges of ensemble e: [chunk, page, first, count] over the loaded segments.
function ensembleRanges(e, out) {
  const L = effectiveL(), f = state.settings.layers, runs = [];
  for (let c = 0; c < chunks.length; ++c) {
    const ch = chunks[c];
    if (!ch) continue;
    const share = f ? f[ch.layer] : 1;
    if (!(share > 0) || !ch.segments.length || !ch.visible) continue;
    runs.length = 0;
    ensembleSlices(ch, L, state.settings.seed, e, share, runs);
    for (let i = 0; i < runs.length; i += 2) {
      for (const s of ch.segments) {
        const b = Math.max(runs[i], s.begin), en = Math.min(runs[i + 1], s.end);
        if (en > b) out.push(c, s.page, s.offset + b - s.begin, en - b);
      }
    }
  }
}
function frame(now) {
  requestAnimationFrame(frame);
  if (!state) return;
  const L = effectiveL();
  if (drawn >= L) return;
  const moving = now - changedAt < 200;
  const start = performance.now();
  let any = false;
  while (drawn < L && ensembleReady(drawn)) {
    if (drawn === 0) {
      clearSums();
      for (let c = 0; c < chunks.length; ++c) if (chunks[c]) chunks[c].visible = chunkVisible(chunks[c]);
    }
    const ranges = [];
    ensembleRanges(drawn, ranges);
    drawEnsemble(drawn, ranges, chunks, proj, clipPlanes(), state.settings);
    drawn += 1;
    any = true;
    // While the camera moves: the first ensembles only; at rest, ~30 ms of work a frame.
    if (moving || performance.now() - start > 30) break;
  }
  if (!any) return;
  show(drawn, L, state.settings);
  if (firstImageAt === null) { firstImageAt = performance.now(); firstImageBytes = bytesReceived; }
  // "converged" only when every page the image wants is in (or left out by the memory budget).
  const missing = missingPages();
  if (drawn === L && !missing) convergedAt = performance.now();
  $('status').textContent = (drawn < L ? 'converging: ' : missing ? 'incomplete, ' + missing + ' missing (named below): '
    : budgetReached ? 'converged within the memory budget: ' : 'converged: ') + drawn + ' / ' + L + ' ensembles · gain ' +
    gain.toFixed(2) + ' · ' + progressText;
}

function png() {
  if (!state || drawn < effectiveL()) return Promise.resolve(null);
  return new Promise((resolve) => canvas.toBlob(resolve, 'image/png'));
}

let replan = null;
const backend = {
  load: loadSite,
  update: (camera, settings) => {
    const before = state;
    setView(camera, settings);
    targets(camera.width, camera.height);
    restart();
    changedAt = performance.now();
    // The loading order follows the camera (at most every 250 ms) and the shown layers.
    if (!before || JSON.stringify(before.settings.layers) !== JSON.stringify(settings.layers)) { planOrder(); pump(); }
    else if (!replan) replan = setTimeout(() => { replan = null; planOrder(); pump(); }, 250);
  },
  pick,
  png,
  api: {
    webgl2: true,
    errors: () => errors.slice(),
    imageRgb,
    // settled: nothing more will be drawn; converged: and nothing is missing.
    progress: () => ({ drawn, L: state ? effectiveL() : 0, converged: !!state && drawn >= effectiveL() && !!convergedAt,
      settled: !!state && drawn >= effectiveL() && !inFlight, missing: groups.length ? missingPages() : '',
      firstImageAt, firstImageBytes, convergedAt, allLoadedAt, bytesReceived, pagesLoaded, heldPoints, budgetPoints,
      pagesFailed: groups.reduce((n, g) => n + g.pages.filter((p) => p.state === 'failed').length, 0) }),
    stats,
    siteRepeatLevel: () => site.data.repeat_level,
  },
};

if (glProblem) {
  $('status').textContent = glProblem + ': the site cannot draw here';
  fail(glProblem);
  window.candiViewer = { webgl2: !!gl, errors: () => errors.slice() };
} else {
  requestAnimationFrame(frame);
  startPage(backend);
}
