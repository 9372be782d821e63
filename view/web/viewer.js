// candi view: the server renders (SPBR on its CPU); this backend of the page (controls.js) sends
// the camera and the settings, and shows the frames it gets back. The server page's entry module
// (index.html); candi publish leaves it out of a site.
import { $ } from './dom.js';
import { startPage } from './controls.js';

// The token came in the address; the page's response set the cookie that authorises its later
// requests (HttpOnly: this script never sees it). The address bar and history keep no token:
// replaced at once (docs/guide/view.md: what the cookie shares).
const token = new URLSearchParams(location.search).get('token') || '';
if (token) history.replaceState(null, '', location.pathname + location.hash);
const canvas = $('view');
const ctx = canvas.getContext('2d');
let socket = null;
let seq = 0, viewSeq = 0, latest = null;
const stats = { framesReceived: 0, lastFrame: null, lastPng: null, sentAt: {}, latencies: [], drawnSeq: -1, drawnFrame: 0 };

// ---- protocol ---------------------------------------------------------------------------
function send(message) {
  if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}
function sendView() {
  if (!latest || !socket || socket.readyState !== WebSocket.OPEN) return;
  seq += 1;
  stats.sentAt[seq] = performance.now();
  viewSeq = seq;
  send({ type: 'view', seq, camera: latest.camera, settings: latest.settings });
}
function connect() {
  const url = (location.protocol === 'https:' ? 'wss://' : 'ws://') + location.host + '/ws?token=' + encodeURIComponent(token);
  socket = new WebSocket(url);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { $('status').textContent = 'connected'; sendView(); };
  socket.onclose = () => { $('status').textContent = 'disconnected: reload the page to reconnect'; };
  socket.onmessage = (event) => {
    if (typeof event.data === 'string') return onText(JSON.parse(event.data));
    onFrame(event.data);
  };
}
const pending = new Map();  // seq -> resolve, for picks and sections
function request(message) {
  return new Promise((resolve) => {
    seq += 1;
    pending.set(seq, { resolve, type: message.type });
    send(Object.assign({ seq }, message));
  });
}
function onText(m) {
  if (m.type === 'scene' && backend.rescene) backend.rescene(m.scene);
  if ((m.type === 'pick' || m.type === 'section') && pending.has(m.seq)) {
    pending.get(m.seq).resolve(m);
    pending.delete(m.seq);
  }
  if (m.type === 'error') {
    $('status').textContent = 'server: ' + m.message;
    // A failed pick or section has no seq: it answers the oldest one waiting.
    for (const [k, p] of pending) { p.resolve(m); pending.delete(k); break; }
  }
}
function onFrame(buffer) {
  const view = new DataView(buffer);
  const n = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, n)));
  const blob = new Blob([new Uint8Array(buffer, 4 + n)], { type: header.format === 'png' ? 'image/png' : 'image/jpeg' });
  stats.framesReceived += 1;
  const arrival = stats.framesReceived;
  if (stats.sentAt[header.seq] !== undefined && (header.ensembles > 0 || header.sample < 1) && !stats.latencies[header.seq]) {
    stats.latencies[header.seq] = performance.now() - stats.sentAt[header.seq];
  }
  createImageBitmap(blob).then((bitmap) => {
    // Decoding finishes out of order (a PNG after the JPEG that followed it): show a frame only
    // if none that arrived after it is shown.
    if (arrival < stats.drawnFrame) { bitmap.close(); return; }
    stats.drawnFrame = arrival;
    stats.drawnSeq = header.seq;
    ctx.drawImage(bitmap, 0, 0);
    bitmap.close();
    stats.lastFrame = header;
    if (header.converged) stats.lastPng = blob;
    const k = header.ensembles, L = header.repeat_level;
    $('bar').style.width = (100 * k / L).toFixed(1) + '%';
    $('status').textContent = (header.converged ? 'converged: ' : 'converging: ') + k + ' / ' + L + ' ensembles · ' +
      (header.sample < 1 ? 'preview of ' + (100 * header.sample).toPrecision(2) + ' % of one ensemble · ' : '') +
      header.render_ms.toFixed(0) + ' ms · gain ' + header.gain.toFixed(2);
  });
}


const backend = {
  load: () => fetch('/api/scene?token=' + encodeURIComponent(token)).then((r) => {
    if (!r.ok) throw new Error('the server refused: ' + r.status + ' (open the address candi view printed)');
    return r.json();
  }).then((s) => { connect(); return s; }),
  update: (camera, settings) => { latest = { camera, settings }; sendView(); },
  pick: (x, y) => request({ type: 'pick', x, y }),
  section: (s) => request({ type: 'section', point: s.point, normal: s.normal, thickness: s.thickness }),
  png: () => Promise.resolve(stats.lastPng && stats.lastFrame && stats.lastFrame.converged ? stats.lastPng : null),
  api: {
    stats,
    // The seq of the last view sent, or -1 while a change waits to be sent.
    viewSeq: () => (window.candiViewer.dirty() || !latest ? -1 : viewSeq),
    canvasPixels: () => Array.from(ctx.getImageData(0, 0, canvas.width, canvas.height).data),
  },
};
startPage(backend);
