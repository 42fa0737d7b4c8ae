/// @file bench_envmap.cpp
/// The environment map's cost per lookup (qsil::EnvironmentLight; docs/architecture.md §11), a
/// table printer. For each EXR given (default: the bundled scenes/envmaps/*.exr, run from the
/// repository root), it builds the
/// emitter as a scene does (scale 1, identity frame) and times, over `--count` random inputs
/// (fixed seed, uniform, so the map's memory is touched as a render's scattered queries touch it):
/// - sample(u): the importance sample (row, column, texel);
/// - eval(d) + pdf(d) of a uniform direction d: what a BSDF-sampled ray that escapes pays for
///   its MIS weight;
/// - eval(d) + pdf(d) of the direction a sample just returned: what a light sample's MIS weight
///   pays when it evaluates the pdf again.
/// Each is the best of `--repeats` passes, in ns per call, on one thread. Before them, the set-up a
/// scene pays once per map: the emitter's construction (texels, sampling weights, Distribution2D)
/// and find_environment_sun, in ms, from the loaded image (the EXR's decoding is not in it): the
/// first build of the map, which a process pays (its memory is touched for the first time), and
/// the best of `--repeats` builds after it. A checksum of the
/// results is printed so that the calls cannot be optimised away, and so that two builds can be
/// compared for equal results (the same checksum: the same samples, radiances and densities).

#include "cli_parse.h"
#include "qsil/environment_light.h"
#include "qsil/environment_sun.h"
#include "qsil/image.h"
#include "qsil/sampling.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

/// Best time of `repeats` runs of f, in ns per call of `count` calls.
template <class F>
double best_ns(int repeats, int count, F&& f) {
  double best = 1e300;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = Clock::now();
    f();
    const double ns = std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / count;
    best = std::min(best, ns);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cost of environment-map sampling and lookups, ns per call (one thread)"};
  std::vector<std::string> files;
  int count = 2000000, repeats = 5;
  app.add_option("maps", files,
                 "EXR environment maps (default: scenes/envmaps/*.exr, relative to the working directory)");
  app.add_option("--count", count, "calls per pass")->check(qsil::cli::positive_number());
  app.add_option("--repeats", repeats, "passes (the best is printed)")->check(qsil::cli::positive_number());
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  if (files.empty() && std::filesystem::is_directory("scenes/envmaps"))
    for (const auto& entry : std::filesystem::directory_iterator("scenes/envmaps"))
      if (entry.path().extension() == ".exr") files.push_back(entry.path().string());
  if (files.empty()) {
    std::fprintf(stderr, "bench_envmap: no maps given and no scenes/envmaps/*.exr in the working directory\n");
    return 2;
  }
  std::sort(files.begin(), files.end());

  std::printf(
      "| map | texels | first build ms | build ms | sample ns | eval+pdf (uniform d) ns | eval+pdf (sampled d) ns | "
      "checksum |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n");
  for (const std::string& file : files) {
    qsil::Environment env;
    env.type = qsil::Environment::Type::EnvMap;
    env.filename = file;
    std::optional<qsil::EnvironmentLight> built;  // a bad map (no R, G, B; a non-finite texel) throws
    double first_ms = 0, build_ms = 1e300, sun_checksum = 0;
    try {
      env.texels = qsil::read_exr(file);
      for (int r = -1; r < repeats; ++r) {
        const auto t0 = Clock::now();
        const qsil::EnvironmentLight again(env);
        const std::optional<qsil::EnvironmentSun> sun = qsil::find_environment_sun(again);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (r < 0)
          first_ms = ms;
        else
          build_ms = std::min(build_ms, ms);
        sun_checksum = sun ? sun->radiance + sun->half_angle + sun->axis.sum() : 0.0;
      }
      built.emplace(env);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_envmap: %s\n", e.what());
      return 1;
    }
    const qsil::EnvironmentLight& light = *built;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::vector<qsil::Vec2> us(static_cast<size_t>(count));
    std::vector<qsil::Vec3> dirs(static_cast<size_t>(count));
    for (int i = 0; i < count; ++i) {
      us[size_t(i)] = qsil::Vec2(uni(rng), uni(rng));
      dirs[size_t(i)] = qsil::square_to_uniform_sphere(qsil::Vec2(uni(rng), uni(rng)));
    }
    std::vector<qsil::Vec3> sampled(static_cast<size_t>(count));
    double sum_sample = 0, sum_uniform = 0, sum_sampled = 0;
    const double t_sample = best_ns(repeats, count, [&] {
      sum_sample = 0;
      for (int i = 0; i < count; ++i) {
        const qsil::EnvironmentLight::Sample s = light.sample(us[size_t(i)]);
        sampled[size_t(i)] = s.dir;
        sum_sample += s.pdf + s.radiance.sum() + s.dir.sum();
      }
    });
    const double t_uniform = best_ns(repeats, count, [&] {
      sum_uniform = 0;
      for (int i = 0; i < count; ++i) sum_uniform += light.eval(dirs[size_t(i)]).sum() + light.pdf(dirs[size_t(i)]);
    });
    const double t_sampled = best_ns(repeats, count, [&] {
      sum_sampled = 0;
      for (int i = 0; i < count; ++i)
        sum_sampled += light.eval(sampled[size_t(i)]).sum() + light.pdf(sampled[size_t(i)]);
    });
    std::printf("| %s | %d x %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.17g |\n",
                std::filesystem::path(file).filename().c_str(), light.width(), light.height(), first_ms, build_ms,
                t_sample, t_uniform, t_sampled, sum_sample + sum_uniform + sum_sampled + sun_checksum);
  }
  return 0;
}
