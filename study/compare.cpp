/// @file compare.cpp
/// The comparison driver; see qsil/study/compare.h.

#include "qsil/study/compare.h"

#include "qsil/error.h"
#include "qsil/files.h"
#include "qsil/image.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

namespace qsil {

namespace {

namespace fs = std::filesystem;

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

/// A number for CSV: %.9g, "null" for non-finite values.
std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

/// A number for JSON: null for non-finite values.
nlohmann::ordered_json json_number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
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

std::string target_text(const CompareOptions& o, double target) {
  return o.equal_time ? "budget " + num(target) + " s" : num(target) + " spp";
}

/// Progressive options of one run: a budget (equal time) or one pass of `target` spp.
ProgressiveOptions progressive_options(const CompareOptions& o, double target, uint64_t seed) {
  ProgressiveOptions po;
  po.seed = seed;
  po.threads = o.threads;
  if (o.equal_time) {
    po.budget_seconds = target;
  } else {
    po.budget_seconds = 0;
    po.max_passes = 1;
    po.fixed_pass_spp = int(std::lround(target));
  }
  return po;
}

/// The estimator configuration of a method.
EstimatorConfig method_config(const Scene& scene, Method m, const std::vector<ParameterSpec>& params,
                              const std::vector<double>& steps, const CompareOptions& o) {
  if (m == Method::FiniteDifferences) return EstimatorConfig::finite_differences(params, steps);
  EstimatorConfig c = EstimatorConfig::gradient(params, m, o.sppi, o.sppp);
  if (m == Method::Regularized) c.regularization = Regularization::for_scene(scene, o.reg_width);
  c.warped_area = o.warped_area;
  c.projective_guiding = o.projective_guiding;
  if (m == Method::Quadric || m == Method::QuadricBox) c.forest_guiding = o.forest_guiding;
  return c;
}

/// The reference: read from options.reference, or rendered with `quadric` (set up by the caller
/// when there is no reference file) for reference_factor times the largest target and written to
/// DIR/reference.exr.
void make_reference(const std::vector<ParameterSpec>& params, const CompareOptions& o, const Estimator* quadric,
                    CompareReport& rep, std::ostream* log) {
  const int K = int(params.size());
  if (!o.reference.empty()) {
    rep.reference = read_reference(o.reference, K, rep.width, rep.height);
    rep.reference_path = o.reference;
    const auto& attrs = rep.reference.image.attributes;
    for (int k = 0; k < K; ++k) {
      auto it = attrs.find("qsil:param" + std::to_string(k));
      if (it != attrs.end() && it->second != params[size_t(k)].text && log)
        *log << "warning: " << o.reference << ": reference parameter " << k << " is '" << it->second << "', comparing '"
             << params[size_t(k)].text << "'\n";
    }
    auto m = attrs.find("qsil:method");
    auto s = attrs.find("qsil:spp");
    rep.reference_description = (m != attrs.end() ? m->second : std::string("?")) + ", " +
                                (s != attrs.end() ? s->second : std::string("?")) + " spp";
    return;
  }
  const ProgressiveOptions po =
      progressive_options(o, o.reference_factor * rep.targets.back(), derive_seed(o.seed, 1 << 30));
  if (log)
    *log << "compare: rendering the reference (quadric, "
         << (o.equal_time ? num(po.budget_seconds) + " s" : std::to_string(po.fixed_pass_spp) + " spp") << ")\n";
  const ProgressiveResult pr = render_progressive([&](const RenderOptions& ro) { return quadric->run(ro); }, po);
  Reference& ref = rep.reference;
  ref.image = reference_image(pr.result);
  ref.image.attributes["qsil:method"] = "reference/quadric";
  ref.image.attributes["qsil:spp"] = std::to_string(pr.result.spp);
  ref.image.attributes["qsil:scene"] = o.scene;
  for (int k = 0; k < K; ++k) ref.image.attributes["qsil:param" + std::to_string(k)] = params[size_t(k)].text;
  ref.num_params = K;
  summarize_reference(ref);
  rep.reference_path = (o.out / "reference.exr").string();
  write_exr(rep.reference_path, ref.image);
  rep.reference_description = "reference/quadric, " + std::to_string(pr.result.spp) + " spp (automatic)";
}

/// Luminance maps of the reference for the grid: dtheta0 and the squared standard error of its
/// luminance (R, G, B errors treated as independent), the per-pixel noise floor of the
/// squared-error maps.
void write_reference_maps(const CompareReport& rep, const fs::path& images) {
  const Image& im = rep.reference.image;
  write_npy(images / "reference.npy", rep.height, rep.width, luminance_plane(im, FilmLayout::derivative_prefix(0)));
  std::vector<float> se2(size_t(rep.width) * rep.height);
  const double w[3] = {luminance(1, 0, 0), luminance(0, 1, 0), luminance(0, 0, 1)};
  for (int c = 0; c < 3; ++c) {
    const auto& p = im.planes[size_t(im.channel_index(FilmLayout::derivative_name(0, c) + ".se"))];
    for (size_t i = 0; i < se2.size(); ++i) se2[i] += float(w[c] * w[c] * double(p[i]) * p[i]);
  }
  write_npy(images / "reference_se2.npy", rep.height, rep.width, se2);
}

/// One method at one target: progressive passes, the error, and at the largest target its images.
CompareRow run_row(const Estimator& est, Method m, double target, uint64_t seed, bool largest,
                   const std::vector<ParameterSpec>& params, const CompareOptions& o, const CompareReport& rep) {
  CompareRow row;
  row.method = m;
  row.target = target;
  row.order = int(rep.rows.size());
  row.run =
      render_progressive([&](const RenderOptions& ro) { return est.run(ro); }, progressive_options(o, target, seed));
  row.err = measure_error(row.run.result.film, rep.reference);
  row.traversals = row.run.result.traversals;
  row.zero_rate = row.traversals > 0 ? double(row.run.result.zero_traversals) / double(row.traversals) : std::nan("");
  if (largest) {
    const std::string name(method_name(m));
    Image img = row.run.result.film.to_image();
    img.attributes["qsil:method"] = name;
    img.attributes["qsil:spp"] = std::to_string(row.run.result.spp);
    img.attributes["qsil:param0"] = params[0].text;
    write_exr(o.out / "images" / (name + ".exr"), img);
    write_npy(o.out / "images" / (name + ".npy"), rep.height, rep.width,
              luminance_plane(img, FilmLayout::derivative_prefix(0)));
  }
  return row;
}

}  // namespace

CompareReport run_compare(const Scene& scene, const std::vector<ParameterSpec>& params, const CompareOptions& o,
                          std::ostream* log) {
  if (o.methods.empty()) throw Error("--methods: no method given");
  if (o.targets.empty()) throw Error("compare: no budget or spp count given");
  CompareReport rep;
  rep.targets = o.targets;
  std::sort(rep.targets.begin(), rep.targets.end());
  rep.width = scene.camera.width;
  rep.height = scene.camera.height;
  rep.fd_steps = fd_steps(scene, params, o.h);
  fs::create_directories(o.out / "images");
  // ---- every method's estimator, set up once for the whole run (quadric also for the reference)
  std::map<Method, std::unique_ptr<Estimator>> estimators;
  auto estimator = [&](Method m) -> const Estimator& {
    auto& e = estimators[m];
    if (!e) {
      e = std::make_unique<Estimator>(scene, method_config(scene, m, params, rep.fd_steps, o));
      if (log) *log << "compare: set up " << method_name(m) << " once: " << e->setup().describe() << "\n";
    }
    return *e;
  };
  for (Method m : o.methods) rep.setups.push_back({m, estimator(m).setup()});
  make_reference(params, o, o.reference.empty() ? &estimator(Method::Quadric) : nullptr, rep, log);
  if (!(rep.reference.mean_sq > 0)) throw Error(rep.reference_path + ": the reference derivative is zero everywhere");
  // ---- the runs: per target, every method once, in an order rotated per target
  const int M = int(o.methods.size());
  const int total = int(rep.targets.size()) * M;
  for (size_t j = 0; j < rep.targets.size(); ++j) {
    for (int i = 0; i < M; ++i) {
      const int mi = (i + int(j)) % M;
      const Method m = o.methods[size_t(mi)];
      const uint64_t seed = derive_seed(o.seed, int(j * 64 + size_t(mi)));
      rep.rows.push_back(run_row(estimator(m), m, rep.targets[j], seed, j + 1 == rep.targets.size(), params, o, rep));
      const CompareRow& row = rep.rows.back();
      if (log) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "compare [%d/%d] %s %s: %d spp in %d pass(es), %.3f s, rel. MSE %.4g%s\n",
                      int(rep.rows.size()), total, target_text(o, row.target).c_str(),
                      std::string(method_name(m)).c_str(), row.run.result.spp, row.run.passes, row.run.wall_seconds,
                      row.err.rel_mse, row.err.nonfinite_pixels ? " NON-FINITE PIXELS" : "");
        *log << buf;
      }
    }
  }
  write_reference_maps(rep, o.out / "images");
  write_compare_results(rep, params, o);
  return rep;
}

namespace {

/// The setup report of method m.
const SetupReport& setup_of(const CompareReport& rep, Method m) {
  for (const CompareSetup& s : rep.setups)
    if (s.method == m) return s.report;
  static const SetupReport none;
  return none;
}

std::string results_csv(const CompareReport& rep, const std::vector<ParameterSpec>& params, const CompareOptions& o) {
  std::ostringstream csv;
  csv << "scene,param,method,mode,target,order,wall_seconds,spp,passes,mse,rel_mse,sum,sum_se,sum_ref,sum_ref_se,"
         "sum_error,nonfinite_pixels,nonfinite_samples,zero_contribution_rate,traversals,noise_floor,rel_noise_floor,"
         "setup_seconds,setup\n";
  const Reference& ref = rep.reference;
  for (const CompareRow& r : rep.rows) {
    const SetupReport& setup = setup_of(rep, r.method);
    csv << csv_field(portable_path(o.scene)) << ',' << csv_field(params[0].text) << ',' << method_name(r.method) << ','
        << (o.equal_time ? "time" : "spp") << ',' << num(r.target) << ',' << r.order << ',' << num(r.run.wall_seconds)
        << ',' << r.run.result.spp << ',' << r.run.passes << ',' << num(r.err.mse) << ',' << num(r.err.rel_mse) << ','
        << num(r.err.sum[0]) << ',' << num(r.err.sum_se[0]) << ',' << num(ref.sum[0]) << ',' << num(ref.sum_se[0])
        << ',' << num(r.err.sum_error[0]) << ',' << r.err.nonfinite_pixels << ',' << r.run.result.nonfinite << ','
        << (std::isfinite(r.zero_rate) ? num(r.zero_rate) : "") << ',' << r.traversals << ',' << num(ref.noise_floor)
        << ',' << num(ref.noise_floor / ref.mean_sq) << ',' << num(setup.seconds) << ',' << csv_field(setup.structure)
        << '\n';
  }
  return csv.str();
}

nlohmann::ordered_json results_json(const CompareReport& rep, const std::vector<ParameterSpec>& params,
                                    const CompareOptions& o) {
  using json = nlohmann::ordered_json;
  const Reference& ref = rep.reference;
  json j;
  j["scene"] = portable_path(o.scene);
  j["defines"] = o.defines;
  j["params"] = json::array();
  for (const ParameterSpec& p : params) j["params"].push_back(p.text);
  j["mode"] = o.equal_time ? "time" : "spp";
  j["targets"] = rep.targets;
  j["methods"] = json::array();
  j["setups"] = json::array();
  for (const CompareSetup& s : rep.setups) {
    j["methods"].push_back(std::string(method_name(s.method)));
    j["setups"].push_back({{"method", std::string(method_name(s.method))},
                           {"seconds", s.report.seconds},
                           {"edge_seconds", s.report.edge_seconds},
                           {"structure", s.report.structure},
                           {"edges", s.report.edges},
                           {"fitted_nodes", s.report.fitted_nodes},
                           {"quadric_nodes", s.report.quadric_nodes},
                           {"primary_edges", s.report.primary_edges}});
  }
  j["fd_steps"] = rep.fd_steps;
  j["resolution"] = {rep.width, rep.height};
  j["machine"] = {
      {"cpu", cpu_model()}, {"hardware_threads", std::thread::hardware_concurrency()}, {"threads", o.threads}};
  j["reference"] = {{"path", portable_path(rep.reference_path)},
                    {"description", rep.reference_description},
                    {"noise_floor", json_number(ref.noise_floor)},
                    {"mean_sq", json_number(ref.mean_sq)},
                    {"rel_noise_floor", json_number(ref.noise_floor / ref.mean_sq)},
                    {"sum", ref.sum},
                    {"sum_se", ref.sum_se}};
  j["rows"] = json::array();
  for (const CompareRow& r : rep.rows) {
    json row = {{"method", std::string(method_name(r.method))},
                {"target", r.target},
                {"order", r.order},
                {"wall_seconds", r.run.wall_seconds},
                {"setup_seconds", setup_of(rep, r.method).seconds},
                {"spp", r.run.result.spp},
                {"passes", r.run.passes},
                {"mse", json_number(r.err.mse)},
                {"rel_mse", json_number(r.err.rel_mse)},
                {"nonfinite_pixels", r.err.nonfinite_pixels},
                {"nonfinite_samples", r.run.result.nonfinite},
                {"zero_contribution_rate", json_number(r.zero_rate)},
                {"traversals", r.traversals}};
    for (const char* key : {"sum", "sum_se", "sum_error"}) row[key] = json::array();
    for (size_t k = 0; k < r.err.sum.size(); ++k) {
      row["sum"].push_back(json_number(r.err.sum[k]));
      row["sum_se"].push_back(json_number(r.err.sum_se[k]));
      row["sum_error"].push_back(json_number(r.err.sum_error[k]));
    }
    j["rows"].push_back(row);
  }
  return j;
}

}  // namespace

void write_compare_results(const CompareReport& report, const std::vector<ParameterSpec>& params,
                           const CompareOptions& options) {
  write_file(options.out / "results.csv", results_csv(report, params, options));
  write_file(options.out / "results.json", results_json(report, params, options).dump(2) + "\n");
}

}  // namespace qsil
