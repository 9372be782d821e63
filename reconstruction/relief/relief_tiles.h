// Seam-free prediction of an image of any size from a predictor of fixed-size square tiles.
//
// Tiles of `tile` pixels overlap by at least `overlap` pixels and are spaced evenly so the last
// one ends at the image border. Each tile's output is weighted by a separable ramp on each side
// that has a neighbouring tile: 0 on the outermost overlap / 4 pixels (the neighbour covers
// them), then sin^2 up to 1 at `overlap` pixels from the edge; 1 elsewhere and on the image's own
// borders. The weighted outputs are averaged: the weights are continuous, so the result has no
// seams where tiles meet, and a predictor whose field is under overlap / 4 pixels is reproduced
// exactly. An image smaller than a tile is
// mirror-padded to one tile. Deterministic; the predictor is called serially.
#pragma once

#include <functional>

#include "core/image.h"
#include "core/progress.h"

namespace candi::relief {

struct TileOptions {
  int tile = 128;     // tile side, pixels, >= 8 (128: the training patch; measured best)
  int overlap = 32;   // minimum overlap of neighbouring tiles, pixels, [0, tile / 2]
  void Check() const;  // throws std::invalid_argument naming the field
};

// Maps a tile x tile one-channel image to a tile x tile one-channel image.
using TilePredictor = std::function<ImageF(const ImageF& tile)>;

// Start offsets of the tiles along an axis of `size` pixels (size >= tile).
std::vector<int> TileStarts(int size, int tile, int overlap);

ImageF PredictTiled(const TileOptions& options, const ImageF& image, const TilePredictor& predict,
                    const ProgressCallback& progress = nullptr);

}  // namespace candi::relief
