// The render archive (render/archive.h): manifest.json, then data-00000.bin, data-00001.bin, ...
// as the input's parts. Opens the archive, then decodes every chunk with hash verification and
// without it (so garbage words are decoded too).
#include <cstdio>

#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "render/archive.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = candi::fuzz::FreshScratchFolder("archive");
  const std::vector<std::string_view> parts = candi::fuzz::SplitParts(data, size, 5);
  candi::fuzz::WriteScratchFile(dir + "/" + candi::render::kArchiveManifest, parts[0]);
  for (size_t k = 1; k < parts.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "/data-%05zu.bin", k - 1);
    candi::fuzz::WriteScratchFile(dir + name, parts[k]);
  }
  try {
    const candi::render::Archive archive(dir);
    candi::PointCloud cloud;
    for (size_t k = 0; k < archive.manifest().chunks.size(); ++k) {
      try {
        archive.ReadChunk(k, &cloud, /*verify=*/true);
      } catch (const candi::InputError&) {
      }
      archive.ReadChunk(k, &cloud, /*verify=*/false);
      archive.Release(k);
    }
  } catch (const candi::InputError&) {
  }
  return 0;
}
