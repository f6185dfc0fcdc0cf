// SPDX-License-Identifier: Apache-2.0
// Internal: recorded image sequences (PNG, TIFF: anything OpenCV's imread
// reads), with their encoder positions from a CSV file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "flatline/common.h"
#include "sources/source.hpp"

namespace flt::sources {

// Reads the CSV (when given) and the first image to learn the frame size.
// `image_bits` is the option source_image_bits (0, 10, 12 or 16, checked by
// the caller). Throws FLT_ERR_IO / FLT_ERR_FORMAT / FLT_ERR_INVALID_ARGUMENT
// naming the file, line or option.
std::unique_ptr<source_impl> make_image_source(std::vector<std::string> paths,
                                               const char *encoder_csv, int image_bits);

// The *.png, *.tif and *.tiff files of `directory` (not its sub-folders),
// sorted by name (byte order), with the folder in front. Throws FLT_ERR_IO
// when the directory cannot be read, FLT_ERR_NOT_FOUND when it holds none.
std::vector<std::string> list_image_files(const std::string &directory);

}  // namespace flt::sources
