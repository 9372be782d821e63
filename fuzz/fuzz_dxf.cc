// DXF import (mesh/dxf_import.h, through dxflib): entities, bulges and units to section pieces.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "mesh/dxf_import.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.dxf", data, size);
  try {
    candi::mesh::ReadDxf(candi::mesh::DxfReadOptions{}, path);
  } catch (const candi::InputError&) {
  }
  return 0;
}
