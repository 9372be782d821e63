// The viewer's page (view/web/), compiled into candi (cmake/EmbedWebAssets.cmake): the server
// serves these and nothing else, so no request can reach the file system.
#pragma once

#include <cstddef>
#include <string>

namespace candi::view {

struct WebAsset {
  const char* path;          // "/index.html"
  const char* content_type;
  const unsigned char* data;
  size_t size;
};

// nullptr when `path` is not an asset.
const WebAsset* FindWebAsset(const std::string& path);
// Every asset (candi publish copies them into the site).
size_t WebAssetCount();
const WebAsset& WebAssetAt(size_t i);

}  // namespace candi::view
