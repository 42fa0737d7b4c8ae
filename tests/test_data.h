#pragma once
/// @file test_data.h
/// Where tests find repository files, independent of the working directory: every path is built
/// from QSIL_SOURCE_DIR, the source tree, a compile definition of the test target only
/// (tests/CMakeLists.txt; the library and the programs never know the source tree).
///
/// A missing file never crashes a test: data_file() and mesh_file() throw std::runtime_error
/// "missing test data file: PATH", and GoogleTest reports an exception thrown in a test body as a
/// failure of that test carrying the message. Helpers that cannot throw (e.g. inside
/// INSTANTIATE_TEST_SUITE_P) must not load data.

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>

namespace qsil::test {

/// Absolute path of a repository file, `relative` to the repository root (e.g.
/// "scenes/spot-mirror.xml"). Does not check that it exists.
inline std::string repo_path(const std::string& relative) {
  return (std::filesystem::path(QSIL_SOURCE_DIR) / relative).string();
}

/// repo_path() of a file that must exist. Throws std::runtime_error("missing test data file:
/// ABSOLUTE_PATH") when it is not a regular file.
inline std::string data_file(const std::string& relative) {
  const std::string path = repo_path(relative);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error("missing test data file: " + path);
  return path;
}

/// The path of a test mesh by file name ("spot.obj", "bob.obj", ...): each mesh lives in the
/// repository once (tests/data/meshes/README.md lists where, with sources and licences). Throws
/// std::runtime_error for an unknown name or a missing file (see data_file()).
inline std::string mesh_file(const std::string& name) {
  static const std::map<std::string, std::string> where = {
      {"spot.obj", "scenes/meshes"},
      {"bunny.obj", "scenes/meshes"},
      {"teapot.obj", "scenes/stability/meshes"},
      {"wingnut.obj", "scenes/stability/meshes"},
      {"bob.obj", "tests/data/meshes"},
      {"torus.obj", "tests/data/meshes"},
  };
  const auto it = where.find(name);
  if (it == where.end()) throw std::runtime_error("unknown test mesh '" + name + "' (see tests/data/meshes/README.md)");
  return data_file(it->second + "/" + name);
}

}  // namespace qsil::test
