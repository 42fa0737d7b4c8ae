/// @file image_io.cpp
/// Image file I/O: OpenEXR (read any channels, write float channels with string attributes) and
/// PNG through stb_image_write. The only file that includes OpenEXR or stb (docs/architecture.md §1).
/// Writes go to a temporary name beside the target and are renamed, so outputs are whole or absent.

#include "qsil/image.h"

#include "qsil/error.h"
#include "qsil/files.h"
#include "qsil/math.h"

#include <Imath/ImathBox.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace qsil {

int Image::channel_index(const std::string& name) const {
  auto it = std::find(channel_names.begin(), channel_names.end(), name);
  return it == channel_names.end() ? -1 : int(it - channel_names.begin());
}

Image read_exr(const std::filesystem::path& path) {
  const std::string name = path.string();
  if (!std::filesystem::exists(path)) throw Error(name + ": file not found");
  try {
    Imf::InputFile file(name.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    Image img;
    img.width = dw.max.x - dw.min.x + 1;
    img.height = dw.max.y - dw.min.y + 1;
    if (img.width <= 0 || img.height <= 0) throw Error(name + ": empty data window");
    Imf::FrameBuffer fb;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
      img.channel_names.push_back(it.name());
      img.planes.emplace_back(size_t(img.width) * img.height, 0.0f);
    }
    for (size_t c = 0; c < img.planes.size(); ++c) {
      char* base = reinterpret_cast<char*>(img.planes[c].data()) -
                   (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * img.width) * ptrdiff_t(sizeof(float));
      fb.insert(img.channel_names[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * size_t(img.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    for (auto it = file.header().begin(); it != file.header().end(); ++it)
      if (std::string(it.attribute().typeName()) == "string")
        img.attributes[it.name()] = static_cast<const Imf::StringAttribute&>(it.attribute()).value();
    return img;
  } catch (const Error&) { throw; } catch (const std::exception& e) {
    std::string msg = e.what();
    if (auto nl = msg.find('\n'); nl != std::string::npos) msg = msg.substr(0, nl);
    throw Error(name + ": cannot read OpenEXR: " + msg);
  }
}

void write_exr(const std::filesystem::path& path, const Image& image) {
  const std::string name = path.string();
  if (image.width <= 0 || image.height <= 0 || image.planes.size() != image.channel_names.size())
    throw Error(name + ": internal: malformed image");
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    try {
      Imf::Header header(image.width, image.height);
      header.compression() = Imf::ZIP_COMPRESSION;
      for (const auto& [k, v] : image.attributes) header.insert(k, Imf::StringAttribute(v));
      Imf::FrameBuffer fb;
      for (size_t c = 0; c < image.planes.size(); ++c) {
        header.channels().insert(image.channel_names[c], Imf::Channel(Imf::FLOAT));
        fb.insert(image.channel_names[c],
                  Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(image.planes[c].data())),
                             sizeof(float), sizeof(float) * size_t(image.width)));
      }
      Imf::OutputFile file(tmp.string().c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(image.height);
    } catch (const std::exception& e) {
      std::string msg = e.what();
      if (auto nl = msg.find('\n'); nl != std::string::npos) msg = msg.substr(0, nl);
      throw Error(name + ": cannot write OpenEXR: " + msg);
    }
  });
}

void write_png(const std::filesystem::path& path, int width, int height, const std::vector<unsigned char>& rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * height * 3)
    throw Error(path.string() + ": internal: malformed PNG data");
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    if (!stbi_write_png(tmp.string().c_str(), width, height, 3, rgb.data(), width * 3))
      throw Error(path.string() + ": cannot write PNG");
  });
}

namespace {
/// A 2D NumPy array of `rows` x `cols` elements of type `descr` ('<f4', '<f8'), `bytes` of data,
/// in format version 1.0, C order, written atomically.
void write_npy_array(const std::filesystem::path& path, const std::string& descr, size_t rows, size_t cols,
                     const char* data, size_t bytes_per_element) {
  std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
                       std::to_string(cols) + "), }";
  // Magic (6) + version (2) + header length (2) + header, padded with spaces to a multiple of 64
  // and ended by a newline.
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  std::string bytes("\x93NUMPY\x01\x00", 8);
  const uint16_t len = uint16_t(header.size());
  bytes.push_back(char(len & 0xff));
  bytes.push_back(char(len >> 8));
  bytes += header;
  bytes.append(data, rows * cols * bytes_per_element);
  write_file(path, bytes);
}
}  // namespace

void write_npy(const std::filesystem::path& path, int height, int width, const std::vector<float>& data) {
  if (height <= 0 || width <= 0 || data.size() != size_t(height) * size_t(width))
    throw Error(path.string() + ": internal: malformed array");
  write_npy_array(path, "<f4", size_t(height), size_t(width), reinterpret_cast<const char*>(data.data()),
                  sizeof(float));
}

void write_npy(const std::filesystem::path& path, size_t rows, size_t cols, const std::vector<double>& data) {
  if (cols == 0 || data.size() != rows * cols) throw Error(path.string() + ": internal: malformed array");
  write_npy_array(path, "<f8", rows, cols, reinterpret_cast<const char*>(data.data()), sizeof(double));
}

std::vector<float> luminance_plane(const Image& image, const std::string& prefix) {
  const std::string p = prefix.empty() ? "" : prefix + ".";
  const int r = image.channel_index(p + "R"), g = image.channel_index(p + "G"), b = image.channel_index(p + "B");
  if (r < 0 || g < 0 || b < 0)
    throw Error("image has no " + (prefix.empty() ? std::string("R,G,B") : prefix) + " channels");
  std::vector<float> out(size_t(image.width) * image.height);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = float(luminance(image.planes[size_t(r)][i], image.planes[size_t(g)][i], image.planes[size_t(b)][i]));
  return out;
}

double linear_to_srgb(double v) {
  if (!(v > 0)) return 0.0;
  if (v >= 1) return 1.0;
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace qsil
