// candi publish: decodes a data page off the main thread. In: {id, name, buffer (the file's
// bytes), points and bytes (site.json's)}. Out: {id, words: Uint32Array (lo, hi of each 8-byte point)} or {id, error}.
// A page is 8 byte planes, gzip-compressed (view/publish.h); a server that decompressed it on the
// way (Content-Encoding) hands over the planes themselves, which are accepted by their length.
'use strict';
self.onmessage = async (event) => {
  const { id, name, buffer, points, bytes } = event.data;
  try {
    let raw = new Uint8Array(buffer);
    if (raw.length !== points * 8) {
      if (raw.length < 18 || raw[0] !== 0x1f || raw[1] !== 0x8b) throw new Error('not a gzip file (' + raw.length + ' bytes)');
      if (raw.length !== bytes) throw new Error('holds ' + raw.length + ' bytes, site.json says ' + bytes + ': truncated or damaged');
      try {
        const stream = new Blob([raw]).stream().pipeThrough(new DecompressionStream('gzip'));
        raw = new Uint8Array(await new Response(stream).arrayBuffer());
      } catch (e) {
        throw new Error('damaged: its gzip data does not decode (CRC-32 or length check)');
      }
      if (raw.length !== points * 8) throw new Error('holds ' + raw.length / 8 + ' points, site.json says ' + points);
    }
    const n = points;
    const words = new Uint32Array(2 * n);
    for (let i = 0; i < n; ++i) {
      words[2 * i] = (raw[i] | (raw[n + i] << 8) | (raw[2 * n + i] << 16) | (raw[3 * n + i] << 24)) >>> 0;
      words[2 * i + 1] = (raw[4 * n + i] | (raw[5 * n + i] << 8) | (raw[6 * n + i] << 16) | (raw[7 * n + i] << 24)) >>> 0;
    }
    self.postMessage({ id, words }, [words.buffer]);
  } catch (e) {
    // DecompressionStream rejects a damaged or truncated stream (gzip's CRC-32 and length).
    self.postMessage({ id, error: name + ': ' + String((e && e.message) || e) });
  }
};
