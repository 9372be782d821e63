// Decodes a LAZ file with npm's laz-perf (the WASM build of laz-perf, an independent LAZ reader)
// and writes its point records, concatenated, to a file. Used by io/laz/laz_write_test.cc.
// Usage: node laz_perf_records.js in.laz out.bin   (laz-perf found through NODE_PATH)
const fs = require('fs');
const { createLazPerf } = require('laz-perf');

async function main() {
  const [input, output] = process.argv.slice(2);
  const bytes = fs.readFileSync(input);
  const L = await createLazPerf();
  const file = L._malloc(bytes.length);
  L.HEAPU8.set(bytes, file);
  const laz = new L.LASZip();
  laz.open(file, bytes.length);
  const count = laz.getCount(), length = laz.getPointLength();
  const point = L._malloc(length);
  const out = Buffer.alloc(count * length);
  for (let i = 0; i < count; ++i) {
    laz.getPoint(point);
    out.set(L.HEAPU8.subarray(point, point + length), i * length);
  }
  fs.writeFileSync(output, out);
  laz.delete();
  L._free(point);
  L._free(file);
}

main().catch((e) => {
  console.error(String(e));
  process.exit(1);
});
