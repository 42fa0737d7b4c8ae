#pragma once
/// @file image.h
/// In-memory float images and their file I/O. src/image_io.cpp is the only file that includes
/// OpenEXR and stb (docs/architecture.md §1).

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace qsil {

/// A planar float image: `channels` named planes of width x height values, row-major with the
/// top row first (y = 0 is the top of the picture, as in EXR and PNG).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::string> channel_names;         ///< e.g. {"R","G","B","dtheta0.R",...}
  std::vector<std::vector<float>> planes;         ///< one plane per channel, width*height values
  std::map<std::string, std::string> attributes;  ///< string header attributes (EXR metadata)

  int channel_index(const std::string& name) const;  ///< -1 if absent
  float& at(int c, int x, int y) { return planes[c][size_t(y) * width + x]; }
  float at(int c, int x, int y) const { return planes[c][size_t(y) * width + x]; }
};

/// Reads an OpenEXR file (any channel set; half or float) into an Image. Channel names are kept.
/// Throws qsil::Error "PATH: <reason>" when the file is missing or not a readable EXR.
Image read_exr(const std::filesystem::path& path);

/// Writes an Image as a float OpenEXR file with its attributes as string header attributes. The
/// file is written to a temporary name beside `path` and renamed, so it is whole or absent.
/// Throws qsil::Error on failure (the temporary is removed).
void write_exr(const std::filesystem::path& path, const Image& image);

/// Writes 8-bit RGB PNG data (width*height*3 bytes, top row first) atomically (temporary + rename).
/// Throws qsil::Error on failure.
void write_png(const std::filesystem::path& path, int width, int height, const std::vector<unsigned char>& rgb);

/// Writes a float32 2D array (height x width, row-major, top row first) as a NumPy .npy file
/// (format version 1.0, C order), atomically. Throws qsil::Error on failure.
void write_npy(const std::filesystem::path& path, int height, int width, const std::vector<float>& data);

/// Writes a float64 2D array (rows x cols, row-major; rows may be 0) as a NumPy .npy file (format
/// version 1.0, C order), atomically. Throws qsil::Error on failure or a size mismatch.
void write_npy(const std::filesystem::path& path, size_t rows, size_t cols, const std::vector<double>& data);

/// The luminance (math.h) of channels prefix.R, prefix.G, prefix.B (prefix "" for R, G, B) of
/// every pixel, row-major, top row first. Throws qsil::Error "image has no PREFIX channels".
std::vector<float> luminance_plane(const Image& image, const std::string& prefix);

/// sRGB transfer function of a linear value, clamped to [0,1] (IEC 61966-2-1).
double linear_to_srgb(double v);

}  // namespace qsil
