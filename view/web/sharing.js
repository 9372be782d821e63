// The view as a file and as an address. view.json: the camera (render/view_json.h) and, under
// "settings", what else makes the image: L, seed, the layers' shares by name, the clipping
// (candi render --view applies them). #view=<base64url of the same JSON> in the address's
// fragment, kept up to date as the view changes: the address reopens the same camera, L, layers'
// shares, clipping, background and brightness (applyShared takes what is valid of it).
import { $ } from './dom.js';
import { finite, vec3 } from './vec.js';
import { scene, camera, settings } from './page.js';

export function viewJson() {
  return JSON.stringify({ projection: camera.projection, width: camera.width, height: camera.height, eye: camera.eye,
    target: camera.target, up: camera.up, fov_y_deg: camera.fov_y_deg, ortho_height: camera.ortho_height,
    near: camera.near, settings: { repeat_level: settings.repeat_level, seed: settings.seed, opaque: settings.opaque,
      point_size: settings.point_size, background: settings.background, brightness: settings.brightness,
      layers: settings.layers, layer_names: scene.layers.map((l) => l.name), clip: settings.clip } }, null, 2) + '\n';
}
function viewState() { return JSON.parse(viewJson()); }
function encode(obj) {
  const bytes = new TextEncoder().encode(JSON.stringify(obj));
  let text = '';
  for (const b of bytes) text += String.fromCharCode(b);
  return btoa(text).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}
function decode(text) {
  const raw = atob(text.replace(/-/g, '+').replace(/_/g, '/'));
  return JSON.parse(new TextDecoder().decode(Uint8Array.from(raw, (c) => c.charCodeAt(0))));
}
export function shareAddress() { return location.href.split('#')[0] + '#view=' + encode(viewState()); }
let addressTimer = null;
// The address follows the view, 300 ms after its last change.
export function scheduleAddress() {
  clearTimeout(addressTimer);
  addressTimer = setTimeout(() => history.replaceState(null, '', location.pathname + location.search + '#view=' + encode(viewState())), 300);
}
// The view the page was opened with (#view=), or null.
export function readAddress() {
  const m = /#view=([A-Za-z0-9_-]+)/.exec(location.hash);
  if (!m) return null;
  try { return decode(m[1]); } catch (e) { $('status').textContent = 'the address\'s view is not readable: ' + e.message; return null; }
}
// Takes what is valid of a shared or saved view; names what is not.
export function applyShared(v) {
  const bad = [];
  const c = v.camera || v;
  if (c.projection === 'perspective' || c.projection === 'orthographic') camera.projection = c.projection;
  for (const k of ['eye', 'target', 'up']) { if (vec3(c[k])) camera[k] = c[k].slice(); else if (k in c) bad.push('camera.' + k); }
  for (const k of ['fov_y_deg', 'ortho_height', 'near']) { if (finite(c[k]) && c[k] > 0) camera[k] = c[k]; else if (k in c) bad.push('camera.' + k); }
  const s = v.settings || {};
  if (Number.isInteger(s.repeat_level) && s.repeat_level >= 1 && s.repeat_level <= 10000) settings.repeat_level = s.repeat_level;
  if (finite(s.point_size) && s.point_size >= 1 && s.point_size <= 64) settings.point_size = s.point_size;
  if (vec3(s.background) && s.background.every((x) => x >= 0 && x <= 255)) settings.background = s.background.map(Math.round);
  if (s.brightness === 'auto' || s.brightness === 'none' || (finite(s.brightness) && s.brightness > 0 && s.brightness <= 100)) settings.brightness = s.brightness;
  if (typeof s.opaque === 'boolean') settings.opaque = s.opaque;
  if (Array.isArray(s.layers)) {
    if (s.layers.length === scene.layers.length && s.layers.every((f) => finite(f) && f >= 0 && f <= 16)) settings.layers = s.layers.slice();
    else bad.push('settings.layers');
  }
  if (Array.isArray(s.clip)) {
    if (s.clip.length <= 16 && s.clip.every((p) => Array.isArray(p) && p.length === 6 && p.every(finite))) settings.clip = s.clip.map((p) => p.slice());
    else bad.push('settings.clip');
  }
  if (bad.length) $('status').textContent = 'the shared view\'s ' + bad.join(', ') + ' not valid: left as they were';
}
export function wireSharing() {
  $('share').addEventListener('click', () => {
    const address = shareAddress();
    history.replaceState(null, '', address);
    if (navigator.clipboard) navigator.clipboard.writeText(address).catch(() => {});
    $('status').textContent = 'this view\'s address is in the address bar (and copied)';
  });
}
