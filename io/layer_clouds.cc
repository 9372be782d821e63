#include "io/layer_clouds.h"

#include <algorithm>
#include <exception>

#include "core/check.h"

namespace candi::io {

void WriteLayerClouds(const std::string& path, const std::vector<PointCloud>& clouds,
                      const std::vector<std::string>& names, const PointWriteOptions& options) {
  CANDI_CHECK(!clouds.empty() && clouds.size() == names.size())
      << "WriteLayerClouds " << path << ": " << clouds.size() << " clouds, " << names.size()
      << " names";
  PointWriteSpec spec{clouds.front().schema, clouds.front().frame, {}, 0};
  std::string comment = "candi_layers";
  for (size_t k = 0; k < clouds.size(); ++k) {
    clouds[k].CheckConsistent();
    spec.count += clouds[k].size();
    comment += " " + std::to_string(k) + "=" + names[k];
  }
  spec.meta.comments.push_back(comment);
  const auto writer = OpenPointWriter(path, spec, options);
  for (const PointCloud& cloud : clouds) writer->Write(cloud);
  writer->Close();
}

std::map<int, std::string> ReadLayerNames(const PointCloudMeta& meta) {
  std::map<int, std::string> names;
  for (const std::string& c : meta.comments) {
    if (c.rfind("candi_layers", 0) != 0) continue;
    size_t p = 12;
    while (p < c.size()) {
      const size_t end = std::min(c.find(' ', p + 1), c.size());
      const std::string item = c.substr(p, end - p);
      const size_t eq = item.find('=');
      if (eq != std::string::npos) {
        try {
          names[std::stoi(item.substr(0, eq))] = item.substr(eq + 1);
        } catch (const std::exception&) {
        }
      }
      p = end;
    }
  }
  return names;
}

}  // namespace candi::io
