#pragma once
/// @file files.h
/// Output files that are whole or absent (docs/architecture.md §3 "Errors and outputs"): every
/// file qsil writes goes through write_atomically(), which writes a temporary file beside the
/// target (same directory, so the rename is atomic) and renames it only when the write succeeded.

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace qsil {

/// Writes `path` by calling `write(temporary)`, which must create the temporary file (beside
/// `path`) and throw on failure; then renames the temporary to `path`. On any failure the
/// temporary is removed and `path` is left as it was. Throws qsil::Error "PATH: cannot write
/// file: REASON" when the rename fails, and rethrows what `write` throws.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temporary)>& write);

/// Writes `contents` (text or bytes, as they are) to `path` through write_atomically. Throws
/// qsil::Error "PATH: cannot write" when the file cannot be created or written.
void write_file(const std::filesystem::path& path, std::string_view contents);

/// A path as written into generated CSV/JSON files: an absolute path becomes relative to the
/// working directory (the repository root when run from there; `..` steps where needed), a
/// relative one is kept (normalised), so the files do not carry one machine's absolute paths.
std::string portable_path(const std::string& path);

}  // namespace qsil
