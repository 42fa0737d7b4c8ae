/// @file cli_common.cpp
/// See cli_common.h.

#include "cli_common.h"

#include "qsil/error.h"
#include "qsil/preview.h"
#include "qsil/ray_tracer.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <vector>

extern char** environ;

namespace qsil::cli {

namespace {
const ProcessGroup* g_group = nullptr;
}  // namespace

void set_process_group(const ProcessGroup& group) { g_group = &group; }

const ProcessGroup& process_group() {
  static const ProcessGroup single;
  return g_group ? *g_group : single;
}

std::string processes_note() {
  const int n = process_group().size();
  return n > 1 ? ", " + std::to_string(n) + " processes" : std::string();
}

void add_scene_options(CLI::App& app, std::string& scene, std::vector<std::string>& defines) {
  app.add_option("scene", scene, "Scene file (Mitsuba 3 XML subset)")->required();
  app.add_option("-D", defines, "Override a scene <default>: -D name=value (repeatable)")->allow_extra_args(false);
}

void add_common_flags(CLI::App& app, CommonFlags& flags, const std::string& default_output) {
  flags.output = default_output;
  add_scene_options(app, flags.scene, flags.defines);
  app.add_option("--spp", flags.render.spp, "Samples per pixel (default: the scene's sampler sample_count)")
      ->check(qsil::cli::positive_number());
  app.add_option("--seed", flags.render.seed, "Random seed; a seed gives bit-identical output for any --threads")
      ->check(qsil::cli::non_negative_number());
  app.add_option("--threads", flags.render.threads, "Worker threads (0 = all cores)")->check(qsil::cli::non_negative_number());
  app.add_option("-o,--output", flags.output, "Output OpenEXR file")->capture_default_str();
  app.add_option("--preview", flags.preview, "Also write a PNG preview to this path");
  app.add_option("--exposure", flags.exposure, "Preview exposure in stops (primal previews)");
  app.add_flag_callback(
      "-q,--quiet", [&flags] { flags.render.progress = false; }, "No progress bar");
}

void add_param_option(CLI::App& app, std::vector<std::string>& params) {
  app.add_option("--param", params,
                 "Parameter (repeatable, 1-8): ID:translate:X,Y,Z | ID:rotate:X,Y,Z[@CX,CY,CZ] (radians) | "
                 "ID:scale[@CX,CY,CZ] (relative) | ID:vertex:INDEX:X,Y,Z; ID is the shape's XML id")
      ->required()
      ->allow_extra_args(false);
}

void add_sample_rate_options(CLI::App& app, double& sppi, double& sppp) {
  app.add_option("--sppi,--boundary-spp", sppi,
                 "Secondary (indirect) boundary-term samples per shading point (Mitsuba 3's sppi; --boundary-spp is "
                 "the old name), on average over a pixel's samples (a fraction "
                 "is a stratified pick of samples: 0.5 = every other sample, weighted 2); 0 = the method's default "
                 "(quadric, quadric-box: 0.5; the others: 1). Quadric and quadric-box split each into ceil(s / 4), at "
                 "most 16, at a shading point moving s times as fast as the mesh's fastest vertex (grazing hits; "
                 "docs/architecture.md §5). For projective: boundary segments per pixel sample, R x width x height "
                 "per sample index (docs/architecture.md §16)")
      ->capture_default_str()
      ->check(qsil::cli::non_negative_number());
  app.add_option("--sppp,--primary-samples", sppp,
                 "Primary boundary-term edge samples per pixel sample (the camera's silhouettes; Mitsuba 3's sppp "
                 "as a ratio to spp; --primary-samples is the old name): R x width x height edge samples per "
                 "sample index, rounded up to a whole chunk of 1024")
      ->capture_default_str()
      ->check(qsil::cli::positive_number());
}

void add_boundary_flags(CLI::App& app, BoundaryFlags& flags, const std::string& method_option,
                        const std::string& method_help, bool curves_flag) {
  app.add_option(method_option, flags.method, method_help)->capture_default_str();
  add_sample_rate_options(app, flags.sppi, flags.sppp);
  add_regularization_options(app, flags.reg_width, "for --boundary regularized");
  add_warped_area_options(app, flags.warped_area, "--boundary was");
  add_projective_guiding_options(app, flags.projective_guiding, "--boundary projective");
  add_forest_guiding_options(app, flags.forest_guiding, "--boundary quadric, quadric-box");
  app.add_option("--camera-hits", flags.camera_hits,
                 "Interior term of camera samples on moving shapes: adaptive (attached where the shading normal "
                 "turns by more than a lobe width across a pixel: thin curved glossy objects, smoothed creases of "
                 "diffuse meshes), attached (the sample follows the surface point it hits everywhere, with the "
                 "matching flux in the primary boundary term; "
                 "docs/architecture.md §4) or detached (the camera ray fixed, as before 2026-11-28). Methods with a "
                 "primary boundary term only")
      ->check(CLI::IsMember({"adaptive", "attached", "detached"}))
      ->capture_default_str();
  app.add_option("--camera-control-spp", flags.camera_control_spp,
                 "Samples per pixel of the primal pre-pass that sets the attached camera hits' control variate (a "
                 "per-pixel constant taken from L in the warp's Jacobian term and flux; unbiased); 0: none, else "
                 "at least 2")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  if (!curves_flag) return;
  bool& intersection_curves = flags.intersection_curves;
  app.add_flag_callback(
      "--no-intersection-curves", [&intersection_curves] { intersection_curves = false; },
      "Do not sample the intersection curves where surfaces cross (to measure what they add: where surfaces "
      "cross, the derivative is then biased)");
}

void add_regularization_options(CLI::App& app, double& width, const std::string& what) {
  app.add_option("--reg-width", width,
                 "Regularised visibility " + what +
                     ": blur width w of a triangle's opacity exp(-d^2 / w^2) at distance d beyond its edges "
                     "(after Quinn 2021), as a fraction of the scene's bounding-box diagonal")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

void add_warped_area_options(CLI::App& app, WarpedAreaSampling& was, const std::string& what) {
  app.add_option("--was-rays", was.rays,
                 "Warped-area sampling (" + what +
                     "): auxiliary rays per warped direction (Bangaru et al. 2020; biased, less with more rays)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--was-kappa", was.kappa,
                 "Warped-area sampling (" + what + "): concentration of the auxiliary rays' von Mises-Fisher lobe")
      ->check(CLI::Range(1.0, 1e8))
      ->capture_default_str();
  app.add_flag("--was-unbiased", was.unbiased,
               "Warped-area sampling (" + what +
                   "): estimate the warp field's limit for infinitely many auxiliary rays without bias (a random "
                   "number of them, 2.2 x --was-rays on average; Blanchet & Glynn 2015's randomised multilevel "
                   "estimator)");
  app.add_option("--was-exponent", was.exponent,
                 "Warped-area sampling (" + what + "): exponent gamma of the harmonic weights (D + B)^-gamma, > 1")
      ->capture_default_str();
}

void add_projective_guiding_options(CLI::App& app, ProjectiveGuiding& guiding, const std::string& what) {
  app.add_option("--guiding-resolution", guiding.resolution,
                 "Projective sampling (" + what +
                     "): cells per axis of the grid that guides its boundary segments (Zhang et al. 2023 §5, as "
                     "Mitsuba 3's guiding=\"grid\"); 0: no guiding (guiding=\"none\")")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--guiding-share", guiding.uniform_share,
                 "Projective sampling (" + what +
                     "): share of the uniform density in the guided mixture (a defensive share: > 0)")
      ->check(CLI::Range(1e-3, 1.0))
      ->capture_default_str();
  app.add_option(
         "--guiding-training", guiding.training,
         "Projective sampling (" + what + "): uniform training segments per pixel of the guide, drawn once at set-up")
      ->check(CLI::Range(1.0 / 1024, 1024.0))
      ->capture_default_str();
  app.add_flag("--guiding-octree", guiding.octree,
               "Projective sampling (" + what +
                   "): guide its boundary segments by an octree learnt from camera paths projected onto nearby "
                   "silhouettes (Zhang et al. 2023 §5.2, as Mitsuba 3's guiding=\"octree\"); excludes "
                   "--guiding-resolution");
  app.add_option("--guiding-seeds", guiding.seeds,
                 "Projective sampling (" + what +
                     "): camera paths per pixel whose projected segments train the octree guide, drawn once at "
                     "set-up (Mitsuba 3's proj_seed_spp; its set-up time grows with the image)")
      ->check(CLI::Range(1.0 / 1024, 1024.0))
      ->capture_default_str();
}

void add_forest_guiding_options(CLI::App& app, ForestGuiding& guiding, const std::string& what) {
  app.add_option("--forest-guide-training", guiding.training,
                 "Guided edge choice (" + what +
                     "): samples per pixel of each training pass of a guide learnt over the edge forest's upper "
                     "levels per region of shading points, drawn at set-up ([QSS] 5.2's future work; "
                     "docs/architecture.md §17); 0: unguided")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  app.add_option("--forest-guide-rounds", guiding.rounds,
                 "Guided edge choice (" + what + "): training passes, each guided by those before it")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--forest-guide-resolution", guiding.guide.resolution,
                 "Guided edge choice (" + what + "): cells per axis of the grid over the training shading points")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--forest-guide-depth", guiding.guide.depth,
                 "Guided edge choice (" + what + "): forest levels below the roots the guide chooses among")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  app.add_option("--forest-guide-share", guiding.guide.share,
                 "Guided edge choice (" + what +
                     "): share of the unguided choice in the guided mixture (a defensive share: > 0)")
      ->check(CLI::Range(1e-3, 1.0))
      ->capture_default_str();
}

EstimatorConfig gradient_config(const Scene& scene, std::vector<ParameterSpec> params, Method method,
                                const BoundaryFlags& flags) {
  EstimatorConfig config = EstimatorConfig::gradient(std::move(params), method, flags.sppi, flags.sppp);
  config.intersection_curves = flags.intersection_curves;
  config.camera_hits = camera_hits_named(flags.camera_hits);
  config.camera_control_spp = flags.camera_control_spp;
  if (method == Method::Regularized)
    config.regularization = Regularization::for_scene(scene, flags.reg_width);
  config.warped_area = flags.warped_area;
  config.projective_guiding = flags.projective_guiding;
  config.forest_guiding = flags.forest_guiding;
  return config;
}

void set_up_estimator(const CommonFlags& flags, const std::vector<std::string>& param_specs,
                      const std::function<EstimatorConfig(const Scene&, const std::vector<ParameterSpec>&)>& make_config,
                      SceneEstimator& out) {
  process_group().all_or_none([&] {
    out.scene.emplace(load_scene_with_flags(flags.scene, flags.defines));
    out.params = parse_parameters(param_specs, *out.scene);
    out.estimator.emplace(*out.scene, make_config(*out.scene, out.params));
  });
}

void add_fd_step_option(CLI::App& app, std::vector<double>& h) {
  app.add_option("--h", h,
                 "Finite-difference step per parameter (one value for all, or one per --param; units of theta: "
                 "scene units per unit direction, radians for rotate, relative for scale). Default: the step "
                 "that moves the parameter's fastest vertex by 1e-3 x the scene's bounding-box diagonal")
      ->allow_extra_args(false);
}

Scene load_scene_with_flags(const std::string& scene_path, const std::vector<std::string>& defines) {
  std::vector<std::string> warnings;
  Scene scene = load_scene(scene_path, parse_defines(defines), &warnings);
  if (process_group().root())
    for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
  return scene;
}

void add_render_attributes(Image& image, const CommonFlags& flags, const RenderResult& r) {
  image.attributes["qsil:scene"] = flags.scene;
  image.attributes["qsil:spp"] = std::to_string(r.spp);
  image.attributes["qsil:seed"] = std::to_string(flags.render.seed);
  image.attributes["qsil:seconds"] = std::to_string(r.seconds);
  std::string defs;
  for (const auto& d : flags.defines) defs += (defs.empty() ? "" : " ") + d;
  if (!defs.empty()) image.attributes["qsil:defines"] = defs;
  if (process_group().size() > 1) image.attributes["qsil:processes"] = std::to_string(process_group().size());
}

void report_nonfinite(const RenderResult& r, uint64_t invalid_rays) {
  if (r.nonfinite > 0)
    std::cerr << "warning: " << r.nonfinite << " sample(s) had a non-finite value and were replaced by 0\n";
  if (invalid_rays > 0)
    std::cerr << "warning: " << invalid_rays << " ray(s) had a non-finite or out-of-range origin, direction or length "
              << "and were treated as misses\n";
}

uint64_t group_invalid_rays() { return process_group().sum(RayTracer::total_invalid_rays()); }

double mrays_per_second(const RenderResult& r) { return r.seconds > 0 ? double(r.rays) / r.seconds * 1e-6 : 0.0; }

void add_scripts_dir_option(CLI::App& app, std::string& scripts_dir) {
  app.add_option("--scripts-dir", scripts_dir,
                 "Directory of the chart scripts (default: $QSIL_SCRIPTS_DIR, else share/qsil beside or above "
                 "the executable)");
}

void add_chart_output_options(CLI::App& app, ChartOutputFlags& flags, const std::string& default_dir) {
  app.add_option("--out-dir", flags.out_dir, "Output directory (default " + default_dir + ")");
  app.add_flag("--no-grid", flags.no_grid, "Skip the labelled grid image (no Python)");
  add_scripts_dir_option(app, flags.scripts_dir);
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
  if (code != 0)
    std::cerr << who << ": warning: " << python << " " << script.string() << " failed (exit " << code << ")\n";
  return code;
}

std::string largest_share_note(const ImageSum& s) {
  if (s.largest_x < 0) return "";
  char buf[96];
  std::snprintf(buf, sizeof buf, "; pixel (%d, %d) holds %.3g %% of its variance", s.largest_x, s.largest_y,
                100 * s.largest_share);
  return buf;
}

void warn_if_dominant_pixel(const std::string& command, int k, const ImageSum& s, const Film& film,
                            bool largest_samples_hint) {
  if (!has_dominant_pixel(s, film)) return;
  std::fflush(stdout);
  std::fprintf(stderr, "qsil %s: warning: %s (--seed)%s\n", command.c_str(), dominant_pixel_warning(s, k).c_str(),
               largest_samples_hint ? ", or list the largest samples with --largest-samples" : "");
}

void write_gradient_outputs(const CommonFlags& flags, const std::vector<ParameterSpec>& params, const RenderResult& r,
                            const std::string& preview_dir, const std::string& command, const std::string& method) {
  const int K = int(params.size());
  Image img = r.film.to_image();
  add_render_attributes(img, flags, r);
  img.attributes["qsil:method"] = method;
  for (int k = 0; k < K; ++k) img.attributes["qsil:param" + std::to_string(k)] = params[size_t(k)].text;
  write_exr(flags.output, img);
  if (!flags.preview.empty()) write_preview_png(flags.preview, img, flags.exposure);
  if (!preview_dir.empty()) std::filesystem::create_directories(preview_dir);
  std::vector<ImageSum> sums;
  for (int k = 0; k < K; ++k) sums.push_back(r.film.derivative_sum(k));
  for (int k = 0; k < K; ++k) {
    const ImageSum& s = sums[size_t(k)];
    std::printf("  dtheta%d (%s): image sum %.6g +- %.3g (1 s.e.%s)", k, params[size_t(k)].text.c_str(), s.sum,
                s.standard_error, largest_share_note(s).c_str());
    if (!preview_dir.empty()) {
      const std::filesystem::path png =
          std::filesystem::path(preview_dir) / (FilmLayout::derivative_prefix(k) + ".png");
      const double range = write_derivative_png(png, img, FilmLayout::derivative_prefix(k));
      std::printf(", preview %s range +-%.4g", png.c_str(), range);
    }
    std::printf("\n");
  }
  if (!preview_dir.empty()) write_preview_png(std::filesystem::path(preview_dir) / "primal.png", img, flags.exposure);
  // After the EXR and previews are written: a failed write ends the command with its one-line error
  // alone (grad's --largest-samples CSV, written later by its caller, is the exception).
  for (int k = 0; k < K; ++k) warn_if_dominant_pixel(command, k, sums[size_t(k)], r.film, command == "grad");
}

}  // namespace qsil::cli
