/// @file cmd_compare.cpp
/// `qsil compare SCENE.xml --param SPEC --methods quadric,quadric-box,vsphere,uniform,fd
/// --budgets 1,2,4 [--reference REF.exr] [--spp-list 4,16] [--h H] --out DIR`: equal-time (or
/// equal-sample) comparison of gradient methods against a reference. Writes DIR/results.csv,
/// DIR/results.json, DIR/images/ (EXR and .npy of each method at the largest budget, the
/// reference) and calls tools/plot_compare.py DIR for error_vs_time.png and grid.png.

#include "cli_common.h"
#include "cli_compare.h"
#include "commands.h"
#include "qsil/error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

namespace qsil::cli {
namespace {

namespace fs = std::filesystem;

/// One measured run: a method at one budget (or spp count).
struct Row {
  std::string method;
  double target = 0;  ///< budget in seconds, or spp in --spp-list mode
  int order = 0;      ///< position in the run sequence
  ProgressiveResult run;
  ErrorMetrics err;
  double zero_rate = std::nan("");  ///< boundary samples that contributed nothing (NaN for fd/none)
  unsigned long long traversals = 0;
};

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const auto c = line.find(':');
      if (c != std::string::npos) return line.substr(c + 2);
    }
  return "unknown";
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

/// A CSV field, quoted (parameter specs contain commas).
std::string csv_field(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"') o += '"';
    o += c;
  }
  return o + "\"";
}

void write_text_atomic(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw Error(path.string() + ": cannot write");
    f << text;
    if (!f) throw Error(path.string() + ": write failed");
  }
  fs::rename(tmp, path);
}

const CommandRegistrar registrar{{"compare", "Equal-time comparison of gradient methods against a reference",
  [](CLI::App& app) -> std::function<int()> {
    struct Flags : CommonFlags {
      std::vector<std::string> params;
      std::vector<std::string> methods{"quadric", "quadric-box", "vsphere", "uniform", "fd"};
      std::vector<double> budgets;
      std::vector<int> spp_list;
      std::string reference;
      std::vector<double> h;
      int boundary_spp = 1;
      std::string out;
      double reference_factor = 8;
      bool no_plot = false;
      std::string scripts_dir;
    };
    auto flags = std::make_shared<Flags>();
    app.add_option("scene", flags->scene, "Scene file (Mitsuba 3 XML subset)")->required();
    app.add_option("-D", flags->defines, "Override a scene <default>: -D name=value (repeatable)")->allow_extra_args(false);
    app.add_option("--seed", flags->render.seed, "Base random seed (each run and pass derives its own)");
    app.add_option("--threads", flags->render.threads, "Worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
    app.add_flag_callback("-q,--quiet", [f = flags.get()] { f->render.progress = false; }, "No per-run progress lines");
    app.add_option("--param", flags->params, "Parameter (repeatable, 1-8), as for `qsil grad`")
        ->required()
        ->allow_extra_args(false);
    app.add_option("--methods", flags->methods,
                   "Comma-separated methods: quadric, quadric-box, vsphere, vsphere-solid, uniform, none, fd")
        ->delimiter(',')
        ->capture_default_str();
    app.add_option("--budgets", flags->budgets, "Comma-separated wall-clock budgets in seconds (equal-time mode)")
        ->delimiter(',')
        ->check(CLI::PositiveNumber);
    app.add_option("--spp-list", flags->spp_list, "Comma-separated spp counts (equal-sample mode, instead of --budgets)")
        ->delimiter(',')
        ->check(CLI::PositiveNumber);
    app.add_option("--reference", flags->reference,
                   "Reference EXR from `qsil reference` (same scene, -D and --param). Without it, a quadric "
                   "reference is rendered first for --reference-factor x the largest budget (or spp) and saved "
                   "as DIR/reference.exr");
    app.add_option("--reference-factor", flags->reference_factor,
                   "Budget (or spp) of the automatic reference relative to the largest budget")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--h", flags->h, "FD step per parameter (one for all, or one per --param); default as `qsil fd`")
        ->allow_extra_args(false);
    app.add_option("--boundary-spp", flags->boundary_spp, "Discontinuity samples per shading point")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    app.add_option("--out", flags->out, "Output directory")->required();
    app.add_flag("--no-plot", flags->no_plot, "Do not call plot_compare.py (the charts)");
    add_scripts_dir_option(app, flags->scripts_dir);
    return [flags]() {
      // ---- inputs
      if (flags->budgets.empty() == flags->spp_list.empty()) throw Error("give exactly one of --budgets and --spp-list");
      if (flags->methods.empty()) throw Error("--methods: no method given");
      const bool equal_time = !flags->budgets.empty();
      std::vector<double> targets = equal_time ? flags->budgets
                                               : std::vector<double>(flags->spp_list.begin(), flags->spp_list.end());
      std::sort(targets.begin(), targets.end());
      std::vector<GradientMethod> methods;
      for (const auto& m : flags->methods) methods.push_back(parse_gradient_method(m));
      const Scene scene = load_scene_with_flags(*flags);
      const auto params = parse_parameters(flags->params, scene);
      const int K = int(params.size());
      const std::vector<double> steps = fd_steps(scene, params, flags->h);
      const fs::path out = flags->out;
      fs::create_directories(out / "images");
      const bool verbose = flags->render.progress;

      // ---- the reference: read, or render with quadric at reference_factor x the largest target
      Reference ref;
      std::string ref_path = flags->reference;
      std::string ref_desc;
      const int width = scene.camera.width, height = scene.camera.height;
      if (!ref_path.empty()) {
        ref = read_reference(ref_path, K, width, height);
        for (int k = 0; k < K; ++k) {
          auto it = ref.image.attributes.find("qsil:param" + std::to_string(k));
          if (it != ref.image.attributes.end() && it->second != params[k].text)
            std::cerr << "warning: " << ref_path << ": reference parameter " << k << " is '" << it->second
                      << "', comparing '" << params[k].text << "'\n";
        }
        auto m = ref.image.attributes.find("qsil:method");
        auto s = ref.image.attributes.find("qsil:spp");
        ref_desc = (m != ref.image.attributes.end() ? m->second : std::string("?")) + ", " +
                   (s != ref.image.attributes.end() ? s->second : std::string("?")) + " spp";
      } else {
        GradientMethod q = parse_gradient_method("quadric");
        ProgressiveOptions po;
        po.seed = progressive_pass_seed(flags->render.seed, 1 << 30);
        po.threads = flags->render.threads;
        if (equal_time) po.budget_seconds = flags->reference_factor * targets.back();
        else {
          po.budget_seconds = 0;
          po.max_passes = 1;
          po.fixed_pass_spp = int(std::lround(flags->reference_factor * targets.back()));
        }
        if (verbose)
          std::cerr << "compare: rendering the reference (quadric, "
                    << (equal_time ? num(po.budget_seconds) + " s" : std::to_string(po.fixed_pass_spp) + " spp")
                    << ")\n";
        const ProgressiveResult pr = render_progressive(make_gradient_pass(scene, params, q, steps, flags->boundary_spp, nullptr), po);
        ref.image = reference_image(pr.result, K);
        ref.image.attributes["qsil:method"] = "reference/quadric";
        ref.image.attributes["qsil:spp"] = std::to_string(pr.result.spp);
        ref.image.attributes["qsil:scene"] = flags->scene;
        for (int k = 0; k < K; ++k) ref.image.attributes["qsil:param" + std::to_string(k)] = params[k].text;
        ref.num_params = K;
        summarize_reference(ref);
        ref_path = (out / "reference.exr").string();
        write_exr(ref_path, ref.image);
        ref_desc = "reference/quadric, " + std::to_string(pr.result.spp) + " spp (automatic)";
      }
      if (!(ref.mean_sq > 0)) throw Error(ref_path + ": the reference derivative is zero everywhere");

      // ---- the runs: per target, every method once, in an order rotated per target
      std::vector<Row> rows;
      const int M = int(methods.size());
      const int total = int(targets.size()) * M;
      for (size_t j = 0; j < targets.size(); ++j) {
        for (int i = 0; i < M; ++i) {
          const int mi = (i + int(j)) % M;
          const GradientMethod& method = methods[mi];
          auto totals = std::make_shared<PassTotals>();
          ProgressiveOptions po;
          po.seed = progressive_pass_seed(flags->render.seed, int(j * 64 + mi));
          po.threads = flags->render.threads;
          if (equal_time) po.budget_seconds = targets[j];
          else {
            po.budget_seconds = 0;
            po.max_passes = 1;
            po.fixed_pass_spp = int(targets[j]);
          }
          Row row;
          row.method = method.name;
          row.target = targets[j];
          row.order = int(rows.size());
          row.run = render_progressive(make_gradient_pass(scene, params, method, steps, flags->boundary_spp, totals), po);
          row.err = measure_error(row.run.result.film, ref);
          row.traversals = totals->report.traversals;
          if (totals->report.traversals > 0)
            row.zero_rate = double(totals->report.zero_traversals) / double(totals->report.traversals);
          if (verbose)
            std::fprintf(stderr, "compare [%d/%d] %s %s: %d spp in %d pass(es), %.3f s, rel. MSE %.4g%s\n",
                         int(rows.size()) + 1, total, equal_time ? ("budget " + num(targets[j]) + " s").c_str()
                                                                 : (num(targets[j]) + " spp").c_str(),
                         method.name.c_str(), row.run.result.spp, row.run.passes, row.run.wall_seconds,
                         row.err.rel_mse, row.err.nonfinite_pixels ? " NON-FINITE PIXELS" : "");
          // Images of the largest target for the grid.
          if (j + 1 == targets.size()) {
            Image img = row.run.result.film.to_image(gradient_channel_names(K));
            img.attributes["qsil:method"] = method.name;
            img.attributes["qsil:spp"] = std::to_string(row.run.result.spp);
            img.attributes["qsil:param0"] = params[0].text;
            write_exr(out / "images" / (method.name + ".exr"), img);
            write_npy(out / "images" / (method.name + ".npy"), height, width, luminance(img, "dtheta0"));
          }
          rows.push_back(std::move(row));
        }
      }
      write_npy(out / "images" / "reference.npy", height, width, luminance(ref.image, "dtheta0"));
      {
        // Squared standard error of the reference's dtheta0 luminance (R,G,B errors treated as
        // independent): the per-pixel noise floor of the squared-error maps.
        std::vector<float> se2(size_t(width) * height);
        const double w[3] = {0.2126, 0.7152, 0.0722};
        for (int c = 0; c < 3; ++c) {
          const auto& p = ref.image.planes[ref.image.channel_index(std::string("dtheta0.") + "RGB"[c] + ".se")];
          for (size_t i = 0; i < se2.size(); ++i) se2[i] += float(w[c] * w[c] * double(p[i]) * p[i]);
        }
        write_npy(out / "images" / "reference_se2.npy", height, width, se2);
      }

      // ---- results.csv and results.json
      std::ostringstream csv;
      csv << "scene,param,method,mode,target,order,wall_seconds,spp,passes,mse,rel_mse,sum,sum_se,sum_ref,sum_ref_se,"
             "sum_error,nonfinite_pixels,nonfinite_samples,zero_contribution_rate,traversals,noise_floor,rel_noise_floor\n";
      for (const Row& r : rows)
        csv << csv_field(portable_path(flags->scene)) << ',' << csv_field(params[0].text) << ',' << r.method << ',' << (equal_time ? "time" : "spp") << ','
            << num(r.target) << ',' << r.order << ',' << num(r.run.wall_seconds) << ',' << r.run.result.spp << ','
            << r.run.passes << ',' << num(r.err.mse) << ',' << num(r.err.rel_mse) << ',' << num(r.err.sum[0]) << ','
            << num(r.err.sum_se[0]) << ',' << num(ref.sum[0]) << ',' << num(ref.sum_se[0]) << ','
            << num(r.err.sum_error[0]) << ',' << r.err.nonfinite_pixels << ',' << r.run.result.nonfinite << ','
            << (std::isfinite(r.zero_rate) ? num(r.zero_rate) : "") << ',' << r.traversals << ','
            << num(ref.noise_floor) << ',' << num(ref.noise_floor / ref.mean_sq) << '\n';
      write_text_atomic(out / "results.csv", csv.str());

      std::ostringstream js;
      js << "{\n  \"scene\": " << json_string(portable_path(flags->scene)) << ",\n  \"defines\": [";
      for (size_t i = 0; i < flags->defines.size(); ++i) js << (i ? ", " : "") << json_string(flags->defines[i]);
      js << "],\n  \"params\": [";
      for (int k = 0; k < K; ++k) js << (k ? ", " : "") << json_string(params[k].text);
      js << "],\n  \"mode\": \"" << (equal_time ? "time" : "spp") << "\",\n  \"targets\": [";
      for (size_t j = 0; j < targets.size(); ++j) js << (j ? ", " : "") << num(targets[j]);
      js << "],\n  \"methods\": [";
      for (int i = 0; i < M; ++i) js << (i ? ", " : "") << json_string(methods[i].name);
      js << "],\n  \"fd_steps\": [";
      for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(steps[k]);
      js << "],\n  \"resolution\": [" << width << ", " << height << "],\n  \"machine\": {\"cpu\": "
         << json_string(cpu_model()) << ", \"hardware_threads\": " << std::thread::hardware_concurrency()
         << ", \"threads\": " << flags->render.threads << "},\n  \"reference\": {\"path\": "
         << json_string(portable_path(ref_path)) << ", \"description\": " << json_string(ref_desc)
         << ", \"noise_floor\": " << num(ref.noise_floor) << ", \"mean_sq\": " << num(ref.mean_sq)
         << ", \"rel_noise_floor\": " << num(ref.noise_floor / ref.mean_sq) << ", \"sum\": [";
      for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(ref.sum[k]);
      js << "], \"sum_se\": [";
      for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(ref.sum_se[k]);
      js << "]},\n  \"rows\": [\n";
      for (size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        js << "    {\"method\": " << json_string(r.method) << ", \"target\": " << num(r.target) << ", \"order\": "
           << r.order << ", \"wall_seconds\": " << num(r.run.wall_seconds) << ", \"spp\": " << r.run.result.spp
           << ", \"passes\": " << r.run.passes << ", \"mse\": " << num(r.err.mse) << ", \"rel_mse\": "
           << num(r.err.rel_mse) << ", \"sum\": [";
        for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(r.err.sum[k]);
        js << "], \"sum_se\": [";
        for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(r.err.sum_se[k]);
        js << "], \"sum_error\": [";
        for (int k = 0; k < K; ++k) js << (k ? ", " : "") << num(r.err.sum_error[k]);
        js << "], \"nonfinite_pixels\": " << r.err.nonfinite_pixels << ", \"nonfinite_samples\": "
           << r.run.result.nonfinite << ", \"zero_contribution_rate\": " << num(r.zero_rate)
           << ", \"traversals\": " << r.traversals << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
      }
      js << "  ]\n}\n";
      write_text_atomic(out / "results.json", js.str());

      // ---- summary: relative MSE per method at the largest target
      std::printf("compare: %s, %s, %d method(s) x %zu %s, reference %s (rel. noise floor %.3g) -> %s\n",
                  flags->scene.c_str(), params[0].text.c_str(), M, targets.size(), equal_time ? "budget(s)" : "spp count(s)",
                  ref_desc.c_str(), ref.noise_floor / ref.mean_sq, (out / "results.csv").c_str());
      for (const Row& r : rows)
        if (r.target == targets.back())
          std::printf("  %-14s %s: %6d spp, %7.3f s, rel. MSE %.4g, image-sum error %.4g (se %.3g), %lld non-finite px\n",
                      r.method.c_str(), equal_time ? ("budget " + num(r.target) + " s").c_str()
                                                   : (num(r.target) + " spp").c_str(),
                      r.run.result.spp, r.run.wall_seconds, r.err.rel_mse, r.err.sum_error[0], r.err.sum_se[0],
                      r.err.nonfinite_pixels);
      std::fflush(stdout);

      // ---- charts (matplotlib, Debian's python3 found on PATH)
      if (!flags->no_plot && run_python_script("compare", "plot_compare.py", {out.string()}, flags->scripts_dir) != 0) {
        std::cerr << "warning: the charts were not drawn; results.csv and results.json are written\n";
        return 1;
      }
      return 0;
    };
  }}};

}  // namespace
}  // namespace qsil::cli
