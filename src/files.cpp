/// @file files.cpp
/// Atomic output files; see qsil/files.h.

#include "qsil/files.h"

#include "qsil/error.h"

#include <unistd.h>

#include <fstream>
#include <random>

namespace qsil {

namespace {
/// A temporary file name beside `path` (same directory, so the rename is atomic), unique per
/// process and call.
std::filesystem::path temporary_beside(const std::filesystem::path& path) {
  std::random_device rd;
  auto tmp = path;
  tmp += ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(rd() % 1000000);
  return tmp;
}
}  // namespace

void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write) {
  const std::filesystem::path tmp = temporary_beside(path);
  std::error_code ec;
  try {
    write(tmp);
  } catch (...) {
    std::filesystem::remove(tmp, ec);
    throw;
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw Error(path.string() + ": cannot write file: " + ec.message());
  }
}

void write_file(const std::filesystem::path& path, std::string_view contents) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path.string() + ": cannot write");
    out.write(contents.data(), std::streamsize(contents.size()));
    out.flush();
    if (!out) throw Error(path.string() + ": cannot write");
  });
}

std::string portable_path(const std::string& path) {
  const std::filesystem::path p(path);
  std::error_code ec;
  const std::filesystem::path cwd = std::filesystem::current_path(ec);
  if (!p.is_absolute() || ec) return p.lexically_normal().string();
  return p.lexically_proximate(cwd).string();
}

}  // namespace qsil
