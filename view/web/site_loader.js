// candi publish: the site's loader. site.json read (no more of it than 256 MB) and checked
// (site_index.js), then the pages (view/publish.h) in ensemble order: page k of every shown
// group (the points ensemble k draws at the site's L) before any page k + 1, groups in view and
// near first, a few at a time, within a budget of points (the finest pages of far groups
// dropped first); each read no further than site.json allows and decoded by a Web Worker
// (site_worker.js). Every problem is named on the page (fail) and the rest is drawn.
import { $ } from './dom.js';
import { check, ensembleSlices } from './site_index.js';
import { state, origin, setFrame, effectiveL, boxInView } from './site_view.js';
import { upload, release } from './site_gl.js';

// ---- problems ------------------------------------------------------------------------------
export const errors = [];
export function fail(message) {
  errors.push(message);
  $('errors').textContent = errors.slice(-6).join('\n') + (errors.length > 6 ? '\n(' + errors.length + ' problems in all)' : '');
}
// What the drawing does when a page of ensemble k arrives or fails (arrived(k)) and when a
// loaded page is dropped (evicted()): the image may have to start again. The site's entry
// (site.js) sets them.
export const hooks = { arrived: (k) => {}, evicted: () => {} };

// ---- the data ------------------------------------------------------------------------------
export let site = null, chunks = [], groups = [];
export let budgetPoints = 0, heldPoints = 0, inFlight = 0, bytesReceived = 0, pagesLoaded = 0;
export let allLoadedAt = null;
let requests = 0;
let worker = null;  // made as loadSite starts
const waiting = new Map();
let nextId = 0;
function decode(name, buffer, points, bytes) {
  return new Promise((resolve) => { const id = nextId++; waiting.set(id, resolve); worker.postMessage({ id, name, buffer, points, bytes }, [buffer]); });
}
const pageName = (g, k) => 'data/' + g + '/' + k + '.bin';
// A response's body, read until it holds more than `most` bytes (then the download is stopped:
// a file larger than site.json says is not this site's page, whatever it would grow to).
async function readAtMost(r, most) {
  const declared = Number(r.headers.get('Content-Length'));
  if (r.headers.get('Content-Encoding') === null && declared > most) {
    throw new Error('is ' + declared + ' bytes, more than the ' + most + ' site.json allows: not this site\'s page');
  }
  const reader = r.body.getReader(), parts = [];
  let n = 0;
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    n += value.length;
    bytesReceived += value.length;
    if (n > most) {
      reader.cancel().catch(() => {});
      throw new Error('is more than the ' + most + ' bytes site.json allows: not this site\'s page (download stopped)');
    }
    parts.push(value);
  }
  const out = new Uint8Array(n);
  let at = 0;
  for (const part of parts) { out.set(part, at); at += part.length; }
  return out.buffer;
}
// Page k of group g: chunk-relative runs, one per chunk, in the file's order.
function pageRuns(g, k) {
  const runs = [];
  for (let c = groups[g].chunks[0]; c < groups[g].chunks[1]; ++c) {
    const out = [];
    ensembleSlices(chunks[c], site.data.repeat_level, site.data.seed, k, 1, out);
    runs.push(out.length ? [out[0], out[1]] : [0, 0]);
  }
  return runs;
}
function loadPage(g, k) {
  const page = groups[g].pages[k];
  page.state = 'loading';
  inFlight += page.points;
  requests += 1;
  let counted = true;
  const landed = () => { if (counted) { inFlight -= page.points; requests -= 1; counted = false; } };
  const name = pageName(g, k);
  return fetch(name).then((r) => {
    if (!r.ok) throw new Error(name + ': HTTP ' + r.status + ' ' + r.statusText);
    // The gzip file, or its planes where a server decompressed them on the way.
    return readAtMost(r, Math.max(page.bytes, 8 * page.points));
  }).then((buffer) => {
    return decode(name, buffer, page.points, page.bytes);
  }).then((m) => {
    landed();
    if (m.error) throw new Error(m.error);
    if (page.state !== 'loading') return;  // evicted meanwhile
    page.words = m.words;
    page.vbo = upload(m.words);
    let offset = 0;
    pageRuns(g, k).forEach(([b, e], i) => {
      if (e > b) chunks[groups[g].chunks[0] + i].segments.push({ begin: b, end: e, page, offset });
      offset += e - b;
    });
    page.state = 'loaded';
    heldPoints += page.points;
    pagesLoaded += 1;
    arrived(k);
  }).catch((e) => {
    landed();
    page.state = 'failed';
    fail(String(e.message || e).startsWith(name) ? String(e.message || e) : name + ': ' + (e.message || e));
    arrived(k);
  });
}
function evict(page) {
  if (page.vbo) release(page.vbo);
  const gr = groups[page.group];
  for (let c = gr.chunks[0]; c < gr.chunks[1]; ++c) chunks[c].segments = chunks[c].segments.filter((s) => s.page !== page);
  heldPoints -= page.points;
  page.vbo = null; page.words = null; page.state = 'none';
}
// A page of ensemble k arrived (or failed): the drawing hears of it, and the next pages load.
function arrived(k) {
  hooks.arrived(k);
  pump();
}

// Priority of page k of group g: lower first. Ensemble order, then groups in view, then near.
function groupDistance(g) {
  const cam = state.camera, b = groups[g].box;
  let d = 0;
  for (let a = 0; a < 3; ++a) { const x = cam.eye[a] - origin[a]; d += Math.max(0, b.min[a] - x, x - b.max[a]) ** 2; }
  return Math.sqrt(d);
}
function groupInView(g) {
  const box = groups[g].box;
  return boxInView(box.min, box.max, 0);
}
function layerShown(g) {
  const f = state.settings.layers;
  for (let c = groups[g].chunks[0]; c < groups[g].chunks[1]; ++c) if (!f || f[chunks[c].layer] > 0) return true;
  return false;
}
// The loading order, ensemble by ensemble (page k of every shown group before any page k + 1),
// the shown groups in rank order; walked from the first ensemble with a page still to load, so
// a pump costs what it loads, not L x groups.
let shownOrder = [], firstOpen = 0;
export function planOrder() {
  if (!state) return;
  const rank = groups.map((_, g) => ({ g, shown: layerShown(g), view: groupInView(g), d: groupDistance(g) }));
  rank.sort((a, b) => (b.shown - a.shown) || (b.view - a.view) || (a.d - b.d));
  const pos = new Array(groups.length);
  rank.forEach((r, i) => { pos[r.g] = i; groups[r.g].wanted = r.shown; });
  shownOrder = rank.filter((r) => r.shown).map((r) => r.g);
  firstOpen = 0;
  groups.forEach((gr, g) => { gr.rank = pos[g]; });
}
const priority = (g, k) => k * groups.length + groups[g].rank;
export function pump() {
  if (!state) return;
  let evictable = null;  // loaded pages, the lowest priority (hidden layers, then finest and far) last
  const L = site.data.repeat_level;
  // (An evicted page ranks below the one loaded instead: it never lies before firstOpen.)
  ensembles: for (let k = firstOpen; k < L; ++k) {
    let open = false;
    for (const g of shownOrder) {
      const page = groups[g].pages[k];
      if (page.state !== 'none') continue;
      open = true;
      if (requests >= 4) break ensembles;  // a few pages at a time, in the order planned
      if (page.points > budgetPoints) {
        // It can never fit: named once with the group's other such pages, and the pages after
        // it still load.
        let n = 0, most = 0;
        for (const p of groups[g].pages) {
          if (p.points > budgetPoints && p.state === 'none') { p.state = 'too large'; n += 1; most = Math.max(most, p.points); }
        }
        fail('data/' + g + '/: ' + n + (n === 1 ? ' page' : ' pages') + ' of up to ' + (most / 1e6).toFixed(2) +
          ' M points, more than the memory budget holds (' + (budgetPoints / 1e6).toFixed(2) + ' M): not loaded');
        continue;
      }
      if (heldPoints + inFlight + page.points > budgetPoints) {
        // Drop the finest pages of far groups first, while they rank below this one.
        if (!evictable) {
          evictable = [];
          groups.forEach((gr, h) => gr.pages.forEach((p, j) => {
            if (p.state === 'loaded') evictable.push({ p, q: gr.wanted ? priority(h, j) : Infinity });
          }));
          evictable.sort((a, b) => a.q - b.q);
        }
        const wp = priority(g, k);
        while (heldPoints + inFlight + page.points > budgetPoints && evictable.length &&
               evictable[evictable.length - 1].q > wp) {
          evict(evictable.pop().p);
          hooks.evicted();
        }
        if (heldPoints + inFlight + page.points > budgetPoints) break ensembles;  // the rest ranks lower still
      }
      loadPage(g, k);
    }
    if (!open && k === firstOpen) firstOpen = k + 1;
  }
  showProgress();
}
// Pages the image lacks that no wait brings: failed, larger than the budget, or in groups
// site.json describes wrongly; as text, or '' when there are none.
export function missingPages() {
  let failed = 0, dropped = 0;
  for (const gr of groups) {
    if (gr.dropped) dropped += 1;
    else if (gr.wanted) for (const p of gr.pages) if (p.state === 'failed' || p.state === 'too large') failed += 1;
  }
  return [failed ? failed + (failed === 1 ? ' page' : ' pages') : '', dropped ? dropped + (dropped === 1 ? ' group' : ' groups') : '']
    .filter((t) => t).join(' and ');
}
export let budgetReached = false;
function showProgress() {
  let want = 0, have = 0, loadable = 0;
  for (const gr of groups) {
    if (!gr.wanted) continue;
    for (const p of gr.pages) {
      want += p.points;
      if (p.state === 'loaded') have += p.points;
      if (p.state !== 'failed' && p.state !== 'too large') loadable += p.points;
    }
  }
  $('bar').style.width = (want ? 100 * have / want : 100).toFixed(1) + '%';
  if (want && (have === want || heldPoints + inFlight >= budgetPoints) && !inFlight && allLoadedAt === null) allLoadedAt = performance.now();
  // Pages that could load but wait for room: the image is what the budget holds.
  budgetReached = have < loadable && !inFlight;
  progressText = (have === want ? 'all ' : '') + (have / 1e6).toFixed(2) + ' of ' + (want / 1e6).toFixed(2) + ' M points loaded (' +
    (bytesReceived / 1e6).toFixed(1) + ' MB)' + (budgetReached ? ' · memory budget reached' : '');
}
export let progressText = '';

// Whether ensemble e can be drawn: the pages it needs that are wanted have arrived (or failed):
// at the site's L, page e of every wanted group; otherwise whatever is loaded.
export function ensembleReady(e) {
  if (effectiveL() !== site.data.repeat_level) return true;
  for (const gr of groups) {
    if (!gr.wanted) continue;
    const p = gr.pages[e];
    if (p.state === 'loading' || (p.state === 'none' && heldPoints + inFlight + p.points <= budgetPoints)) return false;
  }
  return true;
}

// site.json read and checked, the groups and the budget set up: the page's scene (a promise).
export function loadSite() {
  worker = new Worker('site_worker.js');
  worker.onmessage = (e) => { const w = waiting.get(e.data.id); waiting.delete(e.data.id); w(e.data); };
  return fetch('site.json').then((r) => {
    if (!r.ok) throw new Error('site.json: HTTP ' + r.status + ': this folder is not a candi site');
    return readAtMost(r, 256e6).catch((e) => { throw new Error('site.json ' + e.message); });
  }).then((buffer) => {
    let json;
    try { json = JSON.parse(new TextDecoder().decode(buffer)); } catch (e) { throw new Error('site.json is not JSON: ' + e.message); }
    // What is valid of it; one line on the page for each fault.
    let checked;
    try { checked = check(json); } catch (e) { (e.problems || []).forEach(fail); fail(e.message); throw e; }
    checked.problems.forEach(fail);
    const s = checked.site, d = s.data;
    site = s;
    setFrame(s.scene.origin, s.scene.bounds);
    chunks = d.chunks;  // null where a chunk is bad
    groups = d.groups.map((g, gi) => {
      const box = { min: [Infinity, Infinity, Infinity], max: [-Infinity, -Infinity, -Infinity] };
      for (let c = g.chunks[0]; c < g.chunks[1]; ++c) for (let a = 0; a < 3; ++a) {
        box.min[a] = Math.min(box.min[a], chunks[c].min[a]); box.max[a] = Math.max(box.max[a], chunks[c].max[a]);
      }
      return { chunks: g.chunks, box, wanted: !g.dropped, dropped: g.dropped, rank: 0,
        pages: g.pages.map(({ bytes, points }) => ({ bytes, points, state: 'none', group: gi })) };
    });
    // The budget: the address's (a shared link's) when it is in the field's range, else the site's.
    const setBudget = (mb) => {
      budgetPoints = Math.floor(mb * 1e6 / 16);
      for (const gr of groups) for (const p of gr.pages) if (p.state === 'too large' && p.points <= budgetPoints) p.state = 'none';
    };
    const asked = new URLSearchParams(location.search).get('memory_mb');
    let mb = d.memory_mb;
    if (asked !== null) {
      const v = Number(asked);
      if (Number.isFinite(v) && v >= 16 && v <= 65536) mb = v;
      else fail('the address\'s memory_mb=' + asked.slice(0, 40) + ' is not in [16, 65536] MB: the site\'s ' + mb + ' MB is used');
    }
    setBudget(mb);
    $('memory-mb').value = mb;
    $('memory-mb').addEventListener('change', () => {
      const v = Number($('memory-mb').value);
      if (v >= 16 && v <= 65536) { setBudget(v); planOrder(); pump(); }
      else $('memory-mb').value = budgetPoints * 16 / 1e6;
    });
    return s.scene;
  });
}
