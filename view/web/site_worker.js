// candi publish: decodes a data page off the main thread. In: {id, name, buffer (the file's
// bytes), points and bytes (site.json's)}. Out: {id, words: Uint32Array (lo, hi of each 8-byte point)} or {id, error}.
// A page is 8 byte planes, gzip-compressed (view/publish.h); a server that decompressed it on the
// way (Content-Encoding) hands over the planes themselves, which are accepted by their length.
// The gzip stream is inflated piece by piece into the page's 8 x points bytes and stopped as soon
// as it would hold more: a stream that inflates to far more than its page (a gzip bomb) costs at
// most one piece's output, never its whole size.
'use strict';
const PIECE = 16384;  // compressed bytes fed at a time: at most ~16 MB of output each (deflate's 1032:1)

// The gzip stream `raw` inflated into exactly `size` bytes; throws when it holds more or less.
async function inflateInto(raw, size) {
  const stream = new DecompressionStream('gzip');
  const writer = stream.writable.getWriter(), reader = stream.readable.getReader();
  // Fed as the output is read (the stream's backpressure): the input waits while output is unread.
  const feeding = (async () => {
    for (let at = 0; at < raw.length; at += PIECE) await writer.write(raw.subarray(at, at + PIECE));
    await writer.close();
  })();
  feeding.catch(() => {});  // its failure is the reader's (below)
  // Grown as the output arrives, so a page that claims more points than its stream holds costs
  // what the stream holds.
  let out = new Uint8Array(Math.min(size, Math.max(1 << 20, 4 * raw.length)));
  let n = 0, tooLarge = false;
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      if (n + value.length > size) { tooLarge = true; break; }
      if (n + value.length > out.length) {
        const grown = new Uint8Array(Math.min(size, Math.max(2 * out.length, n + value.length)));
        grown.set(out.subarray(0, n));
        out = grown;
      }
      out.set(value, n);
      n += value.length;
    }
  } catch (e) {
    throw new Error('damaged: its gzip data does not decode (CRC-32 or length check)');
  }
  if (tooLarge) {
    reader.cancel().catch(() => {});
    writer.abort().catch(() => {});
    throw new Error('inflates to more than the ' + size + ' bytes of its ' + size / 8 + ' points (site.json): not ' +
      'this site\'s page; inflating stopped');
  }
  if (n !== size) throw new Error('holds ' + n / 8 + ' points, site.json says ' + size / 8);
  return out;
}

self.onmessage = async (event) => {
  const { id, name, buffer, points, bytes } = event.data;
  try {
    let raw = new Uint8Array(buffer);
    if (raw.length !== points * 8) {
      if (raw.length < 18 || raw[0] !== 0x1f || raw[1] !== 0x8b) throw new Error('not a gzip file (' + raw.length + ' bytes)');
      if (raw.length !== bytes) throw new Error('holds ' + raw.length + ' bytes, site.json says ' + bytes + ': truncated or damaged');
      raw = await inflateInto(raw, points * 8);
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
