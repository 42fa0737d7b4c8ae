/// @file cmd_reverse.cpp
/// `qsil reverse SCENE.xml --shape ID... (--adjoint W.exr | --target T.exr) [--boundary METHOD]
/// [--spp N] [--seed S] [-o grad.npy] [--image primal.exr]`: the gradient of a scalar loss with
/// respect to every vertex position of the chosen shapes (reverse mode, qsil/integrators/reverse.h).
/// - `--adjoint W.exr`: the loss is linear, L = sum_x,c W_c(x) I_c(x) (W read from R, G, B).
/// - `--target T.exr`: the L2 loss L = mean over pixel-channels of (I - T)^2. Its adjoint
///   2 (I - T) / (3 W H) needs the image I: a primal render with an independent seed (seed + 1,
///   same spp) gives it, so that the product of the two estimates is unbiased for the gradient of
///   (E[I] - T)^2; the printed loss is that render's (biased upward by its variance).
/// Output: a float64 NumPy array of shape (V, 3), the vertices of the --shape shapes in the order
/// given (each shape's rows are its OBJ vertex order, 0-based), dL/dx in loss units per scene unit.
/// One process only.

#include "cli_common.h"
#include "commands.h"
#include "qsil/error.h"
#include "qsil/integrators/reverse.h"

#include <cmath>
#include <cstdio>

namespace qsil::cli {
namespace {

/// The R, G, B planes of an EXR as a row-major RGB adjoint of the scene's size. Throws qsil::Error
/// naming the option and file for a missing channel or a size mismatch.
std::vector<double> read_rgb(const std::string& option, const std::string& path, const Camera& cam) {
  const Image img = read_exr(path);
  if (img.width != cam.width || img.height != cam.height)
    throw Error(option + " " + path + ": " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                ", the scene renders " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  std::vector<double> out(size_t(img.width) * img.height * 3);
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    const int ch = img.channel_index(names[c]);
    if (ch < 0) throw Error(option + " " + path + ": no channel " + names[c]);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
      const double v = img.planes[size_t(ch)][i];
      if (!std::isfinite(v))
        throw Error(option + " " + path + ": non-finite value at pixel (" + std::to_string(i % size_t(img.width)) +
                    ", " + std::to_string(i / size_t(img.width)) + ")");
      out[3 * i + size_t(c)] = v;
    }
  }
  return out;
}

/// The adjoint of the L2 loss mean (I - T)^2 against the target image of `target_path` (2 (I - T) /
/// n per pixel-channel), I a primal render with seed `render.seed` + 1; `l2` receives that render's
/// loss.
std::vector<double> l2_adjoint(const Scene& scene, const std::string& target_path, const RenderOptions& render,
                               double& l2) {
  const Camera& cam = scene.camera;
  const std::vector<double> target = read_rgb("--target", target_path, cam);
  RenderOptions primal_options = render;
  primal_options.seed = render.seed + 1;
  const RenderResult primal = Estimator(scene, EstimatorConfig::primal()).run(primal_options);
  const double n = double(target.size());
  std::vector<double> w(target.size());
  l2 = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const size_t i = 3 * (size_t(y) * cam.width + x) + size_t(c);
        const double diff = primal.film.mean(FilmLayout().primal(c), x, y) - target[i];
        l2 += diff * diff / n;
        w[i] = 2 * diff / n;
      }
  return w;
}

/// A row-major RGB image (width x height x 3 doubles) as an EXR image with channels R, G, B.
Image rgb_image(const std::vector<double>& rgb, int width, int height) {
  Image img;
  img.width = width;
  img.height = height;
  img.channel_names = {"R", "G", "B"};
  img.planes.assign(3, std::vector<float>(size_t(width) * height));
  for (size_t i = 0; i < img.planes[0].size(); ++i)
    for (int c = 0; c < 3; ++c) img.planes[size_t(c)][i] = float(rgb[3 * i + size_t(c)]);
  return img;
}

const CommandRegistrar registrar{
    {"reverse", "Gradient of a loss with respect to every vertex of chosen shapes (reverse mode)",
     [](CLI::App& app) -> std::function<int()> {
       struct Flags : CommonFlags {
         std::vector<std::string> shapes;
         std::string adjoint, target, image;
         BoundaryFlags boundary;
       };
       auto flags = std::make_shared<Flags>();
       add_common_flags(app, *flags, "grad.npy");
       app.get_option("--output")->description("Output NumPy file: float64 (V, 3), dL/dx per vertex");
       app.add_option("--shape", flags->shapes, "Shape id whose vertex positions are differentiated (repeatable)")
           ->required();
       auto* adj = app.add_option("--adjoint", flags->adjoint, "Adjoint image W (EXR, R, G, B): L = sum W . I");
       auto* tgt = app.add_option("--target", flags->target, "Target image T (EXR, R, G, B): L = mean (I - T)^2");
       adj->excludes(tgt);
       tgt->excludes(adj);
       add_boundary_flags(app, flags->boundary, "--boundary",
                          "Boundary-term estimator: quadric, quadric-box, vsphere, vsphere-solid, uniform, or none "
                          "(interior term only)",
                          true);
       app.add_option("--image", flags->image, "Also write the primal image of the same paths (EXR)");
       return [flags]() {
         if (process_group().size() > 1) throw Error("reverse: runs in one process (no MPI launcher)");
         if (flags->adjoint.empty() && flags->target.empty()) throw Error("reverse: give --adjoint or --target");
         if (flags->boundary.forest_guiding.training > 0)
           throw Error("reverse: --forest-guide-training is forward mode's only (qsil grad)");
         const Method method = parse_method(flags->boundary.method, "--boundary", kBoundaryMethods);
         const Scene scene = load_scene_with_flags(flags->scene, flags->defines);
         const Camera& cam = scene.camera;
         ReverseConfig config{resolve_shapes(scene, flags->shapes), method, flags->boundary.sppi, flags->boundary.sppp,
                              flags->boundary.intersection_curves};
         config.camera_hits = camera_hits_named(flags->boundary.camera_hits);
         config.camera_control_spp = flags->boundary.camera_control_spp;
         const ReverseEstimator reverse(scene, config);
         double l2 = NAN;
         const std::vector<double> w =
             flags->adjoint.empty() ? l2_adjoint(scene, flags->target, flags->render, l2)
                                    : read_rgb("--adjoint", flags->adjoint, cam);
         const ReverseResult r = reverse.run(w, flags->render);
         std::vector<double> rows;
         for (const auto& g : r.gradient)
           for (const Vec3& v : g) rows.insert(rows.end(), {v.x(), v.y(), v.z()});
         write_npy(flags->output, rows.size() / 3, 3, rows);
         if (!flags->image.empty()) write_exr(flags->image, rgb_image(r.image, cam.width, cam.height));
         if (r.nonfinite > 0)
           std::fprintf(stderr, "warning: %llu samples had a non-finite value or gradient and were dropped\n",
                        (unsigned long long)r.nonfinite);
         double norm = 0;
         for (double v : rows) norm += v * v;
         std::printf(
             "reverse: %s %dx%d, %d spp, boundary %s, %.3f s (set-up %.3f s), %llu traversals, %llu replays, "
             "%llu samples probed (no dual numbers)\n",
             flags->scene.c_str(), cam.width, cam.height, r.spp, flags->boundary.method.c_str(),
             reverse.setup().seconds + r.seconds, reverse.setup().seconds, (unsigned long long)r.traversals,
             (unsigned long long)r.replays, (unsigned long long)r.probed);
         std::printf("  set-up: %s\n", reverse.setup().describe().c_str());
         if (std::isnan(l2))
           std::printf("  loss sum W.I = %.9g\n", r.loss);
         else
           std::printf("  loss mean (I - T)^2 = %.9g (render with seed %llu)\n", l2,
                       (unsigned long long)(flags->render.seed + 1));
         size_t row = 0;
         for (size_t i = 0; i < r.gradient.size(); ++i) {
           std::printf("  %s: rows %zu..%zu\n", flags->shapes[i].c_str(), row, row + r.gradient[i].size() - 1);
           row += r.gradient[i].size();
         }
         std::printf("  |dL/dx| = %.6g over %zu vertices -> %s\n", std::sqrt(norm), rows.size() / 3,
                     flags->output.c_str());
         return 0;
       };
     }}};

}  // namespace
}  // namespace qsil::cli
