// The "Layers" panel: each layer's visibility, its points share ×f (its opacity follows the
// point-number law) and "focus" (this layer at full share, the others dimmed), in settings.layers.
import { $ } from './dom.js';
import { scene, settings, changed } from './page.js';

const shown = [];  // the share each layer had before it was hidden
export function buildLayers() {
  const box = $('layers');
  box.textContent = '';
  scene.layers.forEach((l, i) => {
    shown[i] = settings.layers[i] > 0 ? settings.layers[i] : 1;
    const div = document.createElement('div');
    div.className = 'layer';
    div.innerHTML = '<label><input type="checkbox" class="visible"> <span class="name"></span></label>' +
      '<div class="meta"></div><label>points ×<input type="range" class="share" min="0.05" max="3" step="0.05">' +
      '<output class="share-value"></output></label><button class="focus" title="this layer at full share, ' +
      'the others dimmed">focus</button>';
    div.querySelector('.name').textContent = l.name;
    div.querySelector('.meta').textContent = (l.kind ? l.kind + ' · ' : '') + l.points.toLocaleString() + ' points';
    div.querySelector('.visible').id = 'layer-visible-' + i;
    div.querySelector('.share').id = 'layer-share-' + i;
    div.querySelector('.visible').addEventListener('input', (e) => {
      settings.layers[i] = e.target.checked ? shown[i] : 0;
      syncLayers();
      changed();
    });
    div.querySelector('.share').addEventListener('input', (e) => {
      shown[i] = Number(e.target.value);
      if (settings.layers[i] > 0) settings.layers[i] = shown[i];
      syncLayers();
      changed();
    });
    div.querySelector('.focus').addEventListener('click', () => {
      const dim = Math.min(1, Math.max(0, Number($('dim').value) || 0));
      settings.layers = scene.layers.map((_, k) => (k === i ? 1 : (dim > 0 ? dim : 0)));
      settings.layers.forEach((f, k) => { if (f > 0) shown[k] = f; });
      syncLayers();
      changed();
    });
    box.appendChild(div);
  });
  syncLayers();
}
export function syncLayers() {
  scene.layers.forEach((l, i) => {
    const f = settings.layers[i];
    $('layer-visible-' + i).checked = f > 0;
    $('layer-share-' + i).value = f > 0 ? f : shown[i];
    $('layer-share-' + i).parentElement.querySelector('output').textContent = (f > 0 ? f : shown[i]).toFixed(2);
  });
}
export function wireLayers() {
  $('layers-all').addEventListener('click', () => {
    settings.layers = scene.layers.map(() => 1);
    settings.layers.forEach((_, k) => { shown[k] = 1; });
    syncLayers();
    changed();
  });
}
