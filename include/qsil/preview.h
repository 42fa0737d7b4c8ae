#pragma once
/// @file preview.h
/// 8-bit PNG previews of float images: a tonemapped sRGB view of a primal image and a diverging
/// colour map of a derivative (blue negative, white zero, red positive).

#include "qsil/image.h"

#include <filesystem>
#include <string>

namespace qsil {

/// Writes channels R, G, B of `image` scaled by 2^exposure (stops), through the sRGB transfer
/// function, clamped, as a PNG. Throws qsil::Error when the image has no R, G, B channels or the
/// file cannot be written.
void write_preview_png(const std::filesystem::path& path, const Image& image, double exposure);

/// Writes the luminance of the derivative channels prefix.R/G/B of `image` as a diverging PNG
/// (white at zero, toward red for positive and blue for negative values), with the symmetric
/// range set by the 99.5th percentile of |value| (1 when that is 0). Returns that range. Throws
/// qsil::Error when the channels are missing or the file cannot be written.
double write_derivative_png(const std::filesystem::path& path, const Image& image, const std::string& prefix);

}  // namespace qsil
