// candi's page, shared by candi view (the server renders: viewer.js) and candi publish (the
// browser renders with WebGL2: site.js): startPage(backend) wires the page's modules (camera.js,
// input.js, settings.js, layers.js, measure.js, overlay.js, sections.js, sharing.js,
// annotations.js, provenance.js; page.js holds what they share), loads the scene, sends the
// view to the backend once per animation frame when it changed, and gives window.candiViewer to
// tests and scripts. Vectors are arrays [x, y, z] in world metres. A backend object renders:
//   load() -> Promise of the scene (view/source.h's JSON)
//   update(camera, settings)   the image to converge to (called once per animation frame at most)
//   pick(x, y) -> Promise of {hit, point, hits: [{layer, point, depth}]}   shown points only
//   png() -> Promise of the converged PNG (a Blob) or null
//   section(request) -> Promise of the reply (candi view only; absent: no section export)
//   api: what it adds to window.candiViewer (tests and scripts)
// The page sets backend.rescene(scene), which the backend calls when the whole archive replaces
// a preview.
import { $ } from './dom.js';
import { backend, scene, camera, settings, dirty, setBackend, setScene, setCamera, setSettings, changed, sent, clone }
  from './page.js';
import { fitCanvas, project } from './camera.js';
import { wireInput } from './input.js';
import { syncControls, listViews, wireSettings } from './settings.js';
import { buildLayers, syncLayers, wireLayers } from './layers.js';
import { measurements, at, layerName, measureAt, segments, measurementsCsv, stepBehind, wireMeasuring } from './measure.js';
import { drawOverlay } from './overlay.js';
import { lastSection, exportSection, startClipping, wireSections } from './sections.js';
import { shareAddress, scheduleAddress, readAddress, applyShared, viewJson, wireSharing } from './sharing.js';
import { annotations, openAnnotation, buildAnnotations } from './annotations.js';
import { showTitle, buildProvenance, buildLegend } from './provenance.js';

// Sends the view when it changed, once per animation frame.
function pump() {
  if (dirty && camera) {
    sent();
    backend.update(clone(camera), clone(settings));
    scheduleAddress();
  }
  requestAnimationFrame(pump);
}

export function startPage(b) {
  setBackend(b);
  wireInput();
  wireSettings();
  wireLayers();
  wireMeasuring();
  wireSections();
  wireSharing();

  // For tests and scripts (the DevTools protocol reads these).
  const api = {
    viewJson,
    dirty: () => dirty,
    camera: () => clone(camera),
    settings: () => clone(settings),
    setSettings: (s) => { Object.assign(settings, s); syncControls(); syncLayers(); changed(); },
    setCamera: (c) => { Object.assign(camera, c); changed(); },
    pngBase64: () => backend.png().then((blob) => new Promise((resolve) => {
      if (!blob) return resolve('');
      const reader = new FileReader();
      reader.onload = () => resolve(String(reader.result).split(',')[1]);
      reader.readAsDataURL(blob);
    })),
    pick: (x, y) => backend.pick(x, y),
    measureAt,
    measurements: () => measurements.map((m) => ({ layer: layerName(at(m).layer), point: at(m).point, hits: m.hits.length })),
    segments,
    measurementsCsv,
    stepBehind,
    exportSection: (s) => exportSection(s),
    lastSection: () => lastSection,
    project,
    address: () => shareAddress(),
    annotations: () => annotations.slice(),
    flyToAnnotation: (i) => openAnnotation(i),
    status: () => $('status').textContent,
  };
  window.candiViewer = Object.assign(api, backend.api || {});

  backend.load().then((s) => {
    setScene(s);
    document.title = (document.body.classList.contains('site') ? '' : 'candi view · ') + s.title;
    showTitle();
    // candi view FILE: the whole archive replaces a preview (the layers' counts change).
    backend.rescene = (next) => {
      scene.points = next.points;
      scene.chunks = next.chunks;
      scene.preview = next.preview;
      next.layers.forEach((l, i) => { if (scene.layers[i] && scene.layers[i].name === l.name) scene.layers[i].points = l.points; });
      showTitle();
      buildLayers();
    };
    setSettings(clone(s.settings));
    listViews(s.views);
    if (!settings.layers) settings.layers = s.layers.map(() => 1);
    startClipping(s);
    setCamera(clone(s.first_view));
    const shared = readAddress();
    if (shared) applyShared(shared);
    buildLayers();
    buildAnnotations();
    buildProvenance();
    buildLegend();
    // The first view's own size when the window has it (so the first image is candi render's).
    fitCanvas(true);
    syncControls();
    if (!backend.section) $('section-export').hidden = true;
    requestAnimationFrame(pump);
    requestAnimationFrame(drawOverlay);
  }).catch((e) => { $('status').textContent = String(e.message || e); });
}
