// Packing point files coloured by a scalar field (render/archive_pack.h): the colouring resolved
// over every file's values, then readers that replace each point's colour by its value's.
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "render/archive_pack.h"

namespace candi::render {

namespace {

io::PointReadOptions ReadWithFields(const std::string& columns) {
  io::PointReadOptions read;
  read.columns = columns;
  read.scalar_fields = true;
  return read;
}

// A file's points with their colours replaced by a field's. It has no record layout, so the
// packer reads it point by point rather than as raw records.
class FieldColouringReader : public io::PointReader {
 public:
  FieldColouringReader(std::unique_ptr<io::PointReader> inner, const FieldLegend& legend)
      : io::PointReader(inner->path()), inner_(std::move(inner)), legend_(legend) {
    info_ = inner_->info();
    info_.schema.colors = true;
  }
  size_t Read(size_t max_points, PointCloud* chunk) override {
    const size_t n = inner_->Read(max_points, chunk);
    if (n > 0) ColourByField(legend_, FieldValues(*chunk, legend_.field, path_), chunk);
    points_read_ += n;
    return n;
  }

 private:
  std::unique_ptr<io::PointReader> inner_;
  const FieldLegend& legend_;
};

}  // namespace

FieldLegend ResolveFieldColouringOfFiles(const std::vector<std::string>& files, const std::string& columns,
                                         const FieldColouring& colour_by, const ProgressCallback& progress) {
  std::vector<std::unique_ptr<io::PointReader>> readers;
  uint64_t total = 0;
  for (const std::string& file : files) {
    readers.push_back(io::OpenPointReader(file, ReadWithFields(columns)));
    const uint64_t count = readers.back()->info().count;
    if (count != io::kUnknownCount) total += count;
  }
  std::vector<std::vector<double>> values(files.size());
  uint64_t read = 0;
  for (size_t k = 0; k < files.size(); ++k) {
    PointCloud chunk;
    while (readers[k]->Read(size_t{1} << 20, &chunk) > 0) {
      const std::vector<double> v = FieldValues(chunk, colour_by.field, files[k]);
      values[k].insert(values[k].end(), v.begin(), v.end());
      read += v.size();
      if (progress) progress(read, std::max(total, read));
    }
    readers[k].reset();
  }
  std::vector<const std::vector<double>*> pointers;
  for (const auto& v : values) pointers.push_back(&v);
  return ResolveFieldColouring(colour_by, pointers);
}

std::vector<PackInput> PackInputsColouredByField(const std::vector<std::string>& files, const std::string& columns,
                                                 const FieldLegend& legend) {
  std::vector<PackInput> inputs;
  for (const std::string& file : files) {
    inputs.push_back(PackInputFromFile(file, columns));
    inputs.back().open = [file, columns, &legend]() -> std::unique_ptr<io::PointReader> {
      return std::make_unique<FieldColouringReader>(io::OpenPointReader(file, ReadWithFields(columns)), legend);
    };
  }
  return inputs;
}

}  // namespace candi::render
