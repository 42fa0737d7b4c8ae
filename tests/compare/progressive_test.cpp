// Progressive rendering (qsil/study/progressive.h) and `qsil compare` output (run_compare,
// qsil/study/compare.h, through tools/cmd_compare.cpp).
#include "qsil/study/progressive.h"

#include "qsil/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

namespace qsil {
namespace {

Scene tiny_shadow_quad() {
  return load_scene(std::string(QSIL_SOURCE_DIR) + "/scenes/shadow-quad.xml",
                    {{"res", "12"}, {"spp", "1"}, {"max_depth", "2"}});
}

// Fixed passes cover consecutive sample ranges of one seed: the merged film equals merging
// Estimator::run over [0, 2), [2, 4), [4, 6) by hand, bit for bit, and its spp is the sum.
TEST(Progressive, FixedPassesMergeLikeSeparateRanges) {
  const Scene scene = tiny_shadow_quad();
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:0,1,0", scene)};
  const Estimator estimator(scene, EstimatorConfig::gradient(params));
  const PassFunction pass = [&](const RenderOptions& o) { return estimator.run(o); };
  ProgressiveOptions po;
  po.budget_seconds = 0;
  po.fixed_pass_spp = 2;
  po.max_passes = 3;
  po.seed = 17;
  po.threads = 2;
  const ProgressiveResult pr = render_progressive(pass, po);
  EXPECT_EQ(pr.passes, 3);
  EXPECT_EQ(pr.result.spp, 6);
  EXPECT_EQ(pr.result.first_sample, 0);

  RenderOptions o;
  o.spp = 2;
  o.threads = 1;  // results are thread-count independent
  o.progress = false;
  o.seed = 17;
  RenderResult manual = estimator.run(o);
  for (int i = 1; i < 3; ++i) {
    o.first_sample = 2 * i;
    manual.merge(estimator.run(o));
  }
  ASSERT_EQ(manual.film.channels(), pr.result.film.channels());
  for (int c = 0; c < manual.film.channels(); ++c)
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 12; ++x) {
        ASSERT_EQ(pr.result.film.samples(x, y), 6);
        ASSERT_EQ(pr.result.film.mean(c, x, y), manual.film.mean(c, x, y)) << c << " " << x << " " << y;
        ASSERT_EQ(pr.result.film.standard_error(c, x, y), manual.film.standard_error(c, x, y));
      }
  EXPECT_EQ(pr.result.traversals, manual.traversals);
  // Different seeds per method and budget: derived seeds differ.
  EXPECT_NE(derive_seed(17, 0), derive_seed(17, 1));
}

// A budget: passes continue while samples fit and stop near the budget (one predicted pass of
// overshoot at most, plus slack for a loaded CI machine).
TEST(Progressive, StopsAtTheBudget) {
  const Scene scene = tiny_shadow_quad();
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:0,1,0", scene)};
  const Estimator estimator(scene, EstimatorConfig::gradient(params));
  int calls = 0;
  double longest = 0;
  const PassFunction pass = [&](const RenderOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    ++calls;
    RenderResult r = estimator.run(o);
    longest = std::max(longest, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return r;
  };
  ProgressiveOptions po;
  po.budget_seconds = 0.5;
  po.threads = 1;
  const ProgressiveResult pr = render_progressive(pass, po);
  EXPECT_EQ(pr.passes, calls);
  EXPECT_GT(pr.passes, 1);
  EXPECT_GT(pr.result.spp, pr.passes);  // passes grow
  EXPECT_LE(pr.wall_seconds, po.budget_seconds + longest + 0.25);
  EXPECT_GE(pr.wall_seconds, 0.5 * po.budget_seconds);
}

// `qsil compare` in equal-sample mode writes one CSV row per method and spp count.
TEST(CompareCli, CsvHasOneRowPerMethodAndTarget) {
  const auto dir = std::filesystem::temp_directory_path() / ("qsil_compare_test_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string cmd = std::string(QSIL_CLI_PATH) + " compare " + QSIL_SOURCE_DIR +
                          "/scenes/shadow-quad.xml -D res=12 -D max_depth=2 --param object:translate:0,1,0 "
                          "--methods quadric,uniform,fd --spp-list 1,2 --no-plot -q --threads 2 --out " +
                          dir.string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream f(dir / "results.csv");
  std::string line;
  ASSERT_TRUE(std::getline(f, line));
  EXPECT_EQ(line.rfind("scene,param,method,mode,target", 0), 0u);
  std::map<std::string, int> count;
  int rows = 0;
  while (std::getline(f, line)) {
    ++rows;
    // Split on commas outside double quotes (scene and parameter fields are quoted).
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (char ch : line) {
      if (ch == '"')
        quoted = !quoted;
      else if (ch == ',' && !quoted)
        fields.emplace_back();
      else
        fields.back() += ch;
    }
    ASSERT_GE(fields.size(), 5u) << line;
    EXPECT_EQ(fields[1], "object:translate:0,1,0");
    ++count[fields[2] + "@" + fields[4]];
  }
  EXPECT_EQ(rows, 6);
  for (const char* m : {"quadric", "uniform", "fd"})
    for (const char* t : {"1", "2"}) EXPECT_EQ((count[std::string(m) + "@" + t]), 1) << m << " " << t;
  EXPECT_TRUE(std::filesystem::exists(dir / "results.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "reference.exr"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace qsil
