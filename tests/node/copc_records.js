// Reads a COPC file with npm's copc (copc.js, an independent COPC reader that decodes the chunks
// with laz-perf's WASM build): header, info VLR, every hierarchy page and every node's points.
// Writes the nodes' point records, concatenated in hierarchy order, to out.bin and prints one
// JSON line: {"count", "format", "nodes", "pointSum", "spacing", "cube", "depth"}.
// Used by io/copc/copc_write_test.cc. Usage: node copc_records.js in.copc.laz out.bin
// (copc found through NODE_PATH; scripts/node_test_deps.sh installs it).
const fs = require('fs');
const { Copc } = require('copc');

// Every node of the tree, following child pages.
async function allNodes(path, page) {
  const { nodes, pages } = await Copc.loadHierarchyPage(path, page);
  const all = { ...nodes };
  for (const key of Object.keys(pages)) Object.assign(all, await allNodes(path, pages[key]));
  return all;
}

async function main() {
  const [input, output] = process.argv.slice(2);
  const copc = await Copc.create(input);
  const nodes = await allNodes(input, copc.info.rootHierarchyPage);
  const keys = Object.keys(nodes).sort();
  const buffers = [];
  let pointSum = 0, depth = 0;
  for (const key of keys) {
    const node = nodes[key];
    if (!node || node.pointCount === 0) continue;
    const data = await Copc.loadPointDataBuffer(input, copc.header, node);
    if (data.length !== node.pointCount * copc.header.pointDataRecordLength) {
      throw new Error(`node ${key}: ${data.length} bytes for ${node.pointCount} points`);
    }
    buffers.push(Buffer.from(data));
    pointSum += node.pointCount;
    depth = Math.max(depth, Number(key.split('-')[0]));
  }
  fs.writeFileSync(output, Buffer.concat(buffers));
  console.log(JSON.stringify({
    count: copc.header.pointCount,
    format: copc.header.pointDataRecordFormat,
    nodes: keys.length,
    pointSum,
    spacing: copc.info.spacing,
    cube: copc.info.cube,
    depth,
  }));
}

main().catch((e) => {
  console.error(String(e && e.stack ? e.stack : e));
  process.exit(1);
});
