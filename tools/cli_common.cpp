/// @file cli_common.cpp
/// See cli_common.h.

#include "cli_common.h"

#include "qsil/error.h"
#include "qsil/ray_tracer.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <cmath>
#include <iostream>
#include <vector>

extern char** environ;

namespace qsil::cli {

void add_common_flags(CLI::App& app, CommonFlags& flags, const std::string& default_output) {
  flags.output = default_output;
  app.add_option("scene", flags.scene, "Scene file (Mitsuba 3 XML subset)")->required();
  app.add_option("-D", flags.defines, "Override a scene <default>: -D name=value (repeatable)")->allow_extra_args(false);
  app.add_option("--spp", flags.render.spp, "Samples per pixel (default: the scene's sampler sample_count)");
  app.add_option("--seed", flags.render.seed, "Random seed; a seed gives bit-identical output for any --threads");
  app.add_option("--threads", flags.render.threads, "Worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  app.add_option("-o,--output", flags.output, "Output OpenEXR file")->capture_default_str();
  app.add_option("--preview", flags.preview, "Also write a PNG preview to this path");
  app.add_option("--exposure", flags.exposure, "Preview exposure in stops (primal previews)");
  app.add_flag_callback("-q,--quiet", [&flags] { flags.render.progress = false; }, "No progress bar");
}

Scene load_scene_with_flags(const CommonFlags& flags) {
  std::map<std::string, std::string> defaults;
  for (const auto& d : flags.defines) {
    const auto eq = d.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("-D '" + d + "': expected name=value");
    defaults[d.substr(0, eq)] = d.substr(eq + 1);
  }
  std::vector<std::string> warnings;
  Scene scene = load_scene(flags.scene, defaults, &warnings);
  for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
  return scene;
}

void write_preview_png(const std::string& path, const Image& image, double exposure) {
  const int r = image.channel_index("R"), g = image.channel_index("G"), b = image.channel_index("B");
  if (r < 0 || g < 0 || b < 0) throw Error(path + ": image has no R,G,B channels");
  const double scale = std::pow(2.0, exposure);
  std::vector<unsigned char> rgb(size_t(image.width) * image.height * 3);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const size_t i = (size_t(y) * image.width + x) * 3;
      const int ch[3] = {r, g, b};
      for (int c = 0; c < 3; ++c)
        rgb[i + c] = (unsigned char)std::lround(255.0 * linear_to_srgb(scale * image.at(ch[c], x, y)));
    }
  write_png(path, image.width, image.height, rgb);
}

double write_derivative_png(const std::string& path, const Image& image, const std::string& prefix) {
  const int r = image.channel_index(prefix + ".R"), g = image.channel_index(prefix + ".G"),
            b = image.channel_index(prefix + ".B");
  if (r < 0 || g < 0 || b < 0) throw Error(path + ": image has no " + prefix + " channels");
  const size_t n = size_t(image.width) * image.height;
  std::vector<double> lum(n), mags;
  mags.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    lum[i] = 0.2126 * image.planes[r][i] + 0.7152 * image.planes[g][i] + 0.0722 * image.planes[b][i];
    if (std::isfinite(lum[i])) mags.push_back(std::abs(lum[i]));
  }
  double range = 0;
  if (!mags.empty()) {
    const size_t k = std::min(mags.size() - 1, size_t(0.995 * double(mags.size())));
    std::nth_element(mags.begin(), mags.begin() + k, mags.end());
    range = mags[k];
  }
  if (!(range > 0)) range = 1.0;
  std::vector<unsigned char> rgb(n * 3);
  for (size_t i = 0; i < n; ++i) {
    const double t = std::clamp(std::isfinite(lum[i]) ? lum[i] / range : 0.0, -1.0, 1.0);
    // Diverging map: white at zero, toward red (positive) or blue (negative), in sRGB.
    const double a = std::abs(t);
    const double red[3] = {0.70, 0.09, 0.17}, blue[3] = {0.13, 0.40, 0.67};
    const double* end = t >= 0 ? red : blue;
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = (unsigned char)std::lround(255.0 * ((1 - a) * 1.0 + a * end[c]));
  }
  write_png(path, image.width, image.height, rgb);
  return range;
}

void add_render_attributes(Image& image, const CommonFlags& flags, const RenderResult& r) {
  image.attributes["qsil:scene"] = flags.scene;
  image.attributes["qsil:spp"] = std::to_string(r.spp);
  image.attributes["qsil:seed"] = std::to_string(flags.render.seed);
  image.attributes["qsil:seconds"] = std::to_string(r.seconds);
  std::string defs;
  for (const auto& d : flags.defines) defs += (defs.empty() ? "" : " ") + d;
  if (!defs.empty()) image.attributes["qsil:defines"] = defs;
}

void report_nonfinite(const RenderResult& r) {
  if (r.nonfinite > 0)
    std::cerr << "warning: " << r.nonfinite << " sample(s) had a non-finite value and were replaced by 0\n";
  if (const uint64_t invalid = RayTracer::total_invalid_rays(); invalid > 0)
    std::cerr << "warning: " << invalid << " ray(s) had a non-finite or out-of-range origin, direction or length "
              << "and were treated as misses\n";
}

std::string portable_path(const std::string& path) {
  const std::filesystem::path p(path);
  std::error_code ec;
  const std::filesystem::path cwd = std::filesystem::current_path(ec);
  if (!p.is_absolute() || ec) return p.lexically_normal().string();
  return p.lexically_proximate(cwd).string();
}

void add_scripts_dir_option(CLI::App& app, std::string& scripts_dir) {
  app.add_option("--scripts-dir", scripts_dir,
                 "Directory of the chart scripts (default: $QSIL_SCRIPTS_DIR, else share/qsil beside or above "
                 "the executable)");
}

std::filesystem::path find_script(const std::string& name, const std::string& scripts_dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> dirs;
  if (!scripts_dir.empty()) dirs.emplace_back(scripts_dir);
  if (const char* env = std::getenv("QSIL_SCRIPTS_DIR"); env && *env) dirs.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back(exe.parent_path() / "share" / "qsil");
    dirs.push_back(exe.parent_path().parent_path() / "share" / "qsil");
  }
  for (const fs::path& d : dirs)
    if (fs::is_regular_file(d / name, ec)) return d / name;
  return {};
}

int run_python_script(const std::string& who, const std::string& name, const std::vector<std::string>& args,
                      const std::string& scripts_dir) {
  const std::filesystem::path script = find_script(name, scripts_dir);
  if (script.empty()) {
    std::cerr << who << ": warning: " << name << " not found (give --scripts-dir or set QSIL_SCRIPTS_DIR)\n";
    return -1;
  }
  const char* env_python = std::getenv("QSIL_PYTHON");
  const std::string python = env_python && *env_python ? env_python : "python3";
  std::vector<std::string> words{python, script.string()};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
    std::cerr << who << ": warning: cannot run " << python << " (not on PATH? set QSIL_PYTHON) for " << script.string()
              << "\n";
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code != 0) std::cerr << who << ": warning: " << python << " " << script.string() << " failed (exit " << code << ")\n";
  return code;
}

}  // namespace qsil::cli

namespace qsil::cli {

std::vector<ParameterSpec> parse_parameters(const std::vector<std::string>& specs, const Scene& scene) {
  if (specs.empty()) throw Error("at least one --param is required");
  if (specs.size() > size_t(kMaxParameters))
    throw Error("at most " + std::to_string(kMaxParameters) + " --param per run (got " + std::to_string(specs.size()) + ")");
  std::vector<ParameterSpec> params;
  for (const auto& s : specs) params.push_back(parse_parameter(s, scene));
  return params;
}

void write_gradient_outputs(const CommonFlags& flags, const std::vector<ParameterSpec>& params,
                            const RenderResult& r, const std::string& preview_dir, const std::string& method) {
  const int K = int(params.size());
  Image img = r.film.to_image(gradient_channel_names(K));
  add_render_attributes(img, flags, r);
  img.attributes["qsil:method"] = method;
  for (int k = 0; k < K; ++k) img.attributes["qsil:param" + std::to_string(k)] = params[k].text;
  write_exr(flags.output, img);
  if (!flags.preview.empty()) write_preview_png(flags.preview, img, flags.exposure);
  if (!preview_dir.empty()) std::filesystem::create_directories(preview_dir);
  for (int k = 0; k < K; ++k) {
    const ImageSum s = derivative_image_sum(r.film, K, k);
    std::printf("  dtheta%d (%s): image sum %.6g +- %.3g (1 s.e.)", k, params[k].text.c_str(), s.sum, s.standard_error);
    if (!preview_dir.empty()) {
      const std::string png = (std::filesystem::path(preview_dir) / ("dtheta" + std::to_string(k) + ".png")).string();
      const double range = write_derivative_png(png, img, "dtheta" + std::to_string(k));
      std::printf(", preview %s range +-%.4g", png.c_str(), range);
    }
    std::printf("\n");
  }
  if (!preview_dir.empty())
    write_preview_png((std::filesystem::path(preview_dir) / "primal.png").string(), img, flags.exposure);
}

}  // namespace qsil::cli
