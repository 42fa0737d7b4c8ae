/// @file image_io.cpp
/// Image file I/O: OpenEXR (read any channels, write float channels with string attributes) and
/// PNG through stb_image_write. The only file that includes OpenEXR or stb (docs/architecture.md §1).
/// Writes go to a temporary name beside the target and are renamed, so outputs are whole or absent.

#include "qsil/error.h"
#include "qsil/image.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <Imath/ImathBox.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <unistd.h>

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
      fb.insert(img.channel_names[c],
                Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * size_t(img.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    for (auto it = file.header().begin(); it != file.header().end(); ++it)
      if (std::string(it.attribute().typeName()) == "string")
        img.attributes[it.name()] = static_cast<const Imf::StringAttribute&>(it.attribute()).value();
    return img;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    std::string msg = e.what();
    if (auto nl = msg.find('\n'); nl != std::string::npos) msg = msg.substr(0, nl);
    throw Error(name + ": cannot read OpenEXR: " + msg);
  }
}

namespace {
/// A temporary file name beside `path` (same directory, so rename is atomic).
std::filesystem::path temporary_beside(const std::filesystem::path& path) {
  std::random_device rd;
  auto tmp = path;
  tmp += ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(rd() % 1000000);
  return tmp;
}

void commit_file(const std::filesystem::path& tmp, const std::filesystem::path& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(path.string() + ": cannot write file: " + ec.message());
  }
}
}  // namespace

void write_exr(const std::filesystem::path& path, const Image& image) {
  const std::string name = path.string();
  if (image.width <= 0 || image.height <= 0 || image.planes.size() != image.channel_names.size())
    throw Error(name + ": internal: malformed image");
  const auto tmp = temporary_beside(path);
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
    {
      Imf::OutputFile file(tmp.string().c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(image.height);
    }
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    std::string msg = e.what();
    if (auto nl = msg.find('\n'); nl != std::string::npos) msg = msg.substr(0, nl);
    throw Error(name + ": cannot write OpenEXR: " + msg);
  }
  commit_file(tmp, path);
}

void write_png(const std::filesystem::path& path, int width, int height,
               const std::vector<unsigned char>& rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * height * 3)
    throw Error(path.string() + ": internal: malformed PNG data");
  const auto tmp = temporary_beside(path);
  if (!stbi_write_png(tmp.string().c_str(), width, height, 3, rgb.data(), width * 3)) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(path.string() + ": cannot write PNG");
  }
  commit_file(tmp, path);
}

double linear_to_srgb(double v) {
  if (!(v > 0)) return 0.0;
  if (v >= 1) return 1.0;
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace qsil
