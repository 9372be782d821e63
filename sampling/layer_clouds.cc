#include "sampling/layer_clouds.h"

#include "core/check.h"

namespace candi::sampling {

void WriteLayerClouds(const std::string& path, const std::vector<PointCloud>& clouds,
                      const std::vector<std::string>& names, const io::PointWriteOptions& options) {
  CANDI_CHECK(!clouds.empty() && clouds.size() == names.size())
      << "WriteLayerClouds " << path << ": " << clouds.size() << " clouds, " << names.size()
      << " names";
  io::PointWriteSpec spec{clouds.front().schema, clouds.front().frame, {}, 0};
  std::string comment = "candi_layers";
  for (size_t k = 0; k < clouds.size(); ++k) {
    clouds[k].CheckConsistent();
    spec.count += clouds[k].size();
    comment += " " + std::to_string(k) + "=" + names[k];
  }
  spec.meta.comments.push_back(comment);
  const auto writer = io::OpenPointWriter(path, spec, options);
  for (const PointCloud& cloud : clouds) writer->Write(cloud);
  writer->Close();
}

}  // namespace candi::sampling
