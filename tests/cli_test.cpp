// The `qsil` program as a user meets it: exit codes and one-line errors for bad input, no partial
// output files, deterministic images across thread counts. Runs the built binary.
#include "qsil/image.h"
#include "shell_run.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

namespace {

using CliRun = qsil::testing::ShellRun;

/// Runs `qsil ARGS` from the repository root, capturing stdout and stderr.
CliRun run_qsil(const std::string& args) {
  return qsil::testing::run_shell(std::string(QSIL_CLI_PATH) + " " + args, "qsil_cli_test");
}

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_" + name)).string();
}

/// A bad invocation exits 2 with exactly one line on stderr containing `needle`, and writes no output.
void expect_error(const std::string& args, const std::string& needle) {
  const std::string out = tmp("qsil_cli_should_not_exist.exr");
  std::filesystem::remove(out);
  const CliRun r = run_qsil(args + " -q -o " + out);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\nstderr: " << r.err;
  EXPECT_FALSE(std::filesystem::exists(out)) << args;
}

}  // namespace

TEST(CLI, SceneErrorsExitWithCode2AndOneLineNamingFileAndLine) {
  expect_error("render tests/data/scenes/bad_plugin.xml", "bad_plugin.xml:");
  expect_error("render tests/data/scenes/bad_plugin.xml", "unsupported plugin");
  expect_error("render tests/data/scenes/bad_malformed.xml", "bad_malformed.xml:");
  expect_error("render tests/data/scenes/bad_missing_obj.xml", "not found");
  expect_error("render tests/data/scenes/bad_noface_obj.xml", "no faces");
  expect_error("render tests/data/scenes/bad_nan_obj.xml", "non-finite");
  expect_error("render tests/data/scenes/bad_conductor_preset.xml", "preset");
  expect_error("render tests/data/scenes/does_not_exist.xml", "does_not_exist.xml");
  expect_error("render scenes/shadow-quad.xml -D spp", "-D 'spp'");
}

TEST(CLI, ParameterErrorsExitWithCode2) {
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param nosuch:translate:0,1,0", "no shape with id 'nosuch'");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,0,0", "zero direction");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:vertex:99999999:0,1,0", "out of range");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1", "X,Y,Z");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:wobble:1", "unknown kind");
  expect_error("fd scenes/shadow-quad.xml --spp 1 --param object:rotate:0,1,0 --h -1", "step");
}

// Numbers out of their range are bad input like any other: one line naming the flag, exit 2, no
// output (a sample count of 0 or -3 once rendered the scene's default silently).
TEST(CLI, OutOfRangeNumbersExitWithCode2NamingTheFlag) {
  expect_error("render scenes/shadow-quad.xml --spp 0", "--spp");
  expect_error("render scenes/shadow-quad.xml --spp -3", "--spp");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1,0 --spp 0", "--spp");
  expect_error("render scenes/shadow-quad.xml --spp 1 --threads -1", "--threads");
  expect_error("render scenes/shadow-quad.xml --spp 1 --seed -3", "--seed");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1,0 --sppi -1", "--sppi");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1,0 --primary-samples 0",
               "--sppp");
}

// --sppi is Mitsuba 3's name of the secondary boundary samples; --boundary-spp, the old name, sets
// the same value: the two images are bit-identical, and differ from the default's.
TEST(CLI, SppiAndItsOldNameBoundarySppAreTheSameSetting) {
  const std::string a = tmp("qsil_sppi.exr"), b = tmp("qsil_boundary_spp.exr"), c = tmp("qsil_sppi_default.exr");
  const std::string common =
      "grad scenes/shadow-quad.xml -q -D res=16 --spp 2 --seed 5 --param object:translate:1,0,0 --boundary quadric ";
  ASSERT_EQ(run_qsil(common + "--sppi 3 -o " + a).code, 0);
  ASSERT_EQ(run_qsil(common + "--boundary-spp 3 -o " + b).code, 0);
  ASSERT_EQ(run_qsil(common + "-o " + c).code, 0);
  const qsil::Image ia = qsil::read_exr(a), ib = qsil::read_exr(b), ic = qsil::read_exr(c);
  const int k = ia.channel_index("dtheta0.R");
  ASSERT_GE(k, 0);
  const auto& pa = ia.planes[size_t(k)];
  EXPECT_EQ(0, std::memcmp(pa.data(), ib.planes[size_t(k)].data(), pa.size() * sizeof(float)));
  EXPECT_NE(0, std::memcmp(pa.data(), ic.planes[size_t(k)].data(), pa.size() * sizeof(float)));
}

// Repeatable options take one value each, wherever they stand relative to the scene argument.
TEST(CLI, RepeatedOptionsBeforeTheSceneDoNotSwallowIt) {
  const std::string out = tmp("qsil_order.exr");
  const CliRun r = run_qsil(
      "fd --param object:translate:0,1,0 --param light:translate:1,0,0 -D res=8 "
      "scenes/shadow-quad.xml -q --spp 1 -o " +
      out);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(qsil::read_exr(out).channel_names.size(), 9u);
}

TEST(CLI, HelpExplainsEveryCommandAndExitsZero) {
  for (const char* cmd : {"render", "grad", "fd"}) {
    const CliRun r = run_qsil(std::string(cmd) + " --help");
    EXPECT_EQ(r.code, 0) << cmd;
    EXPECT_NE(r.out.find("--spp"), std::string::npos) << cmd;
    EXPECT_NE(r.out.find("--seed"), std::string::npos) << cmd;
  }
}

// Same seed, 1 vs 2 threads: identical pixel bytes (the EXR header differs only in its timing).
TEST(CLI, RenderIsBitIdenticalForAnyThreadCount) {
  const std::string a = tmp("qsil_det_1.exr"), b = tmp("qsil_det_2.exr");
  const std::string common = "render scenes/shadow-quad.xml -q -D res=24 --spp 4 --seed 9 ";
  ASSERT_EQ(run_qsil(common + "--threads 1 -o " + a).code, 0);
  const CliRun r = run_qsil(common + "--threads 2 -o " + b);
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("Mrays/s"), std::string::npos);  // the final summary line
  const qsil::Image ia = qsil::read_exr(a), ib = qsil::read_exr(b);
  ASSERT_EQ(ia.planes.size(), ib.planes.size());
  for (size_t c = 0; c < ia.planes.size(); ++c)
    EXPECT_EQ(0, std::memcmp(ia.planes[c].data(), ib.planes[c].data(), ia.planes[c].size() * sizeof(float)));
}

// The gradient too, boundary term included (its primary splats are merged in a fixed order).
TEST(CLI, GradIsBitIdenticalForAnyThreadCount) {
  const std::string a = tmp("qsil_gdet_1.exr"), b = tmp("qsil_gdet_2.exr");
  const std::string common =
      "grad scenes/shadow-quad.xml -q -D res=16 --spp 2 --seed 5 --param object:translate:1,0,0 --boundary quadric ";
  ASSERT_EQ(run_qsil(common + "--threads 1 -o " + a).code, 0);
  ASSERT_EQ(run_qsil(common + "--threads 2 -o " + b).code, 0);
  const qsil::Image ia = qsil::read_exr(a), ib = qsil::read_exr(b);
  ASSERT_EQ(ia.planes.size(), ib.planes.size());
  for (size_t c = 0; c < ia.planes.size(); ++c)
    EXPECT_EQ(0, std::memcmp(ia.planes[c].data(), ib.planes[c].data(), ia.planes[c].size() * sizeof(float)))
        << ia.channel_names[c];
}

// grad writes R,G,B and dtheta<k>.R/G/B per parameter, with the specs as header attributes, and
// one diverging preview per parameter.
TEST(CLI, GradWritesTheDocumentedChannelsAttributesAndPreviews) {
  const std::string out = tmp("qsil_grad_layout.exr"), dir = tmp("qsil_grad_previews");
  std::filesystem::remove_all(dir);
  const CliRun r = run_qsil(
      "grad scenes/shadow-quad.xml -q -D res=16 --spp 2 --param object:translate:0,1,0 "
      "--param light:rotate:1,0,0 -o " +
      out + " --preview-dir " + dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const qsil::Image img = qsil::read_exr(out);
  for (const char* ch : {"R", "G", "B", "dtheta0.R", "dtheta0.G", "dtheta0.B", "dtheta1.R", "dtheta1.G", "dtheta1.B"})
    EXPECT_GE(img.channel_index(ch), 0) << ch;
  EXPECT_EQ(img.channel_names.size(), 9u);
  EXPECT_EQ(img.attributes.at("qsil:param0"), "object:translate:0,1,0");
  EXPECT_EQ(img.attributes.at("qsil:param1"), "light:rotate:1,0,0");
  EXPECT_TRUE(std::filesystem::exists(dir + "/dtheta0.png"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/dtheta1.png"));
  EXPECT_NE(r.out.find("image sum"), std::string::npos);
}

// Each image sum names the pixel that holds the largest share of its variance, and grad, fd and
// reference warn (one line on stderr, exit 0, the image written) exactly where that share is 50 %
// or more (kDominantPixelShare): checked on shadow-quad at seed 1 on a 4 x 4 film, where one pixel
// dominates (74-100 %), and on 32 x 32 and 48 x 48 ones, where none does at this seed (7-29 %); at
// least one run of each kind, or the check has no power.
TEST(CLI, GradFdAndReferenceWarnWhereOnePixelHoldsMostOfTheImageSumsVariance) {
  int warned = 0, quiet = 0;
  for (const std::string cmd : {"grad", "fd", "reference"})
    for (const char* film : {"-D res=4 --spp 4", "-D res=32 --spp 8", "-D res=48 --spp 4"}) {
      const std::string out = tmp("qsil_dominant_pixel.exr");
      std::filesystem::remove(out);
      const CliRun r =
          run_qsil(cmd + " scenes/shadow-quad.xml -q " + film + " --seed 1 --param object:translate:0,1,0 -o " + out);
      ASSERT_EQ(r.code, 0) << cmd << " " << film << "\n" << r.err;
      EXPECT_TRUE(std::filesystem::exists(out));
      int x = -1, y = -1;
      double share = -1;
      const size_t at = r.out.find("; pixel (");
      ASSERT_NE(at, std::string::npos) << r.out;
      ASSERT_EQ(std::sscanf(r.out.c_str() + at, "; pixel (%d, %d) holds %lf %%", &x, &y, &share), 3) << r.out;
      const bool warns = r.err.find("warning: dtheta0: pixel (") != std::string::npos;
      EXPECT_EQ(warns, share >= 50.0) << cmd << " " << film << ": " << share << " %\n" << r.err;
      if (warns) {
        ++warned;
        EXPECT_NE(r.err.find("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") holds"), std::string::npos)
            << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_EQ(r.err.find("--largest-samples") != std::string::npos, cmd == "grad") << r.err;
      } else {
        ++quiet;
      }
    }
  EXPECT_GE(warned, 1);
  EXPECT_GE(quiet, 1);
}

// --largest-samples K prints the K largest samples with their path vertices and writes the CSV
// beside it (one row per vertex); the CSV without K is bad input.
TEST(CLI, GradReportsTheLargestSamples) {
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1,0 --largest-samples-csv x.csv",
               "--largest-samples");
  expect_error("grad scenes/shadow-quad.xml --spp 1 --param object:translate:0,1,0 --largest-samples -2",
               "--largest-samples");
  const std::string out = tmp("qsil_grad_largest.exr"), csv = tmp("qsil_grad_largest.csv");
  const CliRun r = run_qsil("grad scenes/shadow-quad.xml -q -D res=16 --spp 2 --param object:translate:0,1,0 -o " + out +
                            " --largest-samples 3 --largest-samples-csv " + csv);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("#3 pixel ("), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("#4 pixel ("), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("vertex 1 on "), std::string::npos) << r.out;
  std::FILE* f = std::fopen(csv.c_str(), "r");
  ASSERT_NE(f, nullptr);
  std::array<char, 256> line{};
  ASSERT_NE(std::fgets(line.data(), int(line.size()), f), nullptr);
  EXPECT_EQ(std::string(line.data()).rfind("rank,x,y,sample,param,value,interior,boundary", 0), 0u) << line.data();
  int rows = 0;
  while (std::fgets(line.data(), int(line.size()), f)) ++rows;
  std::fclose(f);
  EXPECT_GE(rows, 3);
}

TEST(CLI, ReverseErrorsExitWithCode2) {
  const std::string target = tmp("qsil_reverse_target.exr");
  ASSERT_EQ(run_qsil("render scenes/shadow-quad.xml -q -D res=16 --spp 1 -o " + target).code, 0);
  expect_error("reverse scenes/shadow-quad.xml --spp 1 --shape nosuch --target " + target,
               "--shape 'nosuch': no shape with this id");
  expect_error("reverse scenes/shadow-quad.xml --spp 1 -D res=8 --shape object --target " + target,
               "16x16, the scene renders 8x8");
  expect_error("reverse scenes/shadow-quad.xml --spp 1 -D res=16 --shape object", "give --adjoint or --target");
  expect_error("reverse scenes/shadow-quad.xml --spp 1 -D res=16 --shape object --boundary fd --target " + target,
               "--boundary");
  expect_error(
      "reverse scenes/shadow-quad.xml --spp 1 -D res=16 --shape object --camera-control-spp 1 --target " + target,
      "at least 2 pre-pass spp (got 1)");
}

TEST(CLI, ReverseTakesGradsCameraHitsAndControlVariate) {
  // The set-up line says what was built: attached camera hits and their control variate, as
  // `qsil grad` builds them; without the pre-pass no control; detached, neither.
  const std::string target = tmp("qsil_reverse_target3.exr"), out = tmp("qsil_reverse3.npy");
  ASSERT_EQ(run_qsil("render scenes/shadow-quad.xml -q -D res=16 --spp 1 -o " + target).code, 0);
  const std::string run = "reverse scenes/shadow-quad.xml -q -D res=16 --spp 1 --shape object --target " + target +
                          " -o " + out + " --camera-hits ";
  const CliRun attached = run_qsil(run + "attached");
  ASSERT_EQ(attached.code, 0) << attached.err;
  EXPECT_NE(attached.out.find("camera hits attached at"), std::string::npos) << attached.out;
  EXPECT_NE(attached.out.find("a control variate at"), std::string::npos) << attached.out;
  const CliRun uncontrolled = run_qsil(run + "attached --camera-control-spp 0");
  ASSERT_EQ(uncontrolled.code, 0) << uncontrolled.err;
  EXPECT_NE(uncontrolled.out.find("camera hits attached at"), std::string::npos) << uncontrolled.out;
  EXPECT_EQ(uncontrolled.out.find("a control variate"), std::string::npos) << uncontrolled.out;
  const CliRun detached = run_qsil(run + "detached");
  ASSERT_EQ(detached.code, 0) << detached.err;
  EXPECT_EQ(detached.out.find("camera hits attached"), std::string::npos) << detached.out;
}

TEST(CLI, ReverseWritesOneGradientRowPerVertex) {
  const std::string target = tmp("qsil_reverse_target2.exr"), out = tmp("qsil_reverse.npy");
  ASSERT_EQ(run_qsil("render scenes/shadow-quad.xml -q -D res=16 --spp 1 -o " + target).code, 0);
  const CliRun r =
      run_qsil("reverse scenes/shadow-quad.xml -q -D res=16 --spp 2 --shape object --shape light --target " + target +
               " -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("loss mean (I - T)^2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("light: rows "), std::string::npos) << r.out;
  // The NumPy header: float64, (object's vertices + the light's 4, 3).
  std::FILE* f = std::fopen(out.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  std::array<char, 128> head{};
  const size_t n = std::fread(head.data(), 1, head.size(), f);
  std::fclose(f);
  const std::string header(head.data(), n);
  EXPECT_NE(header.find("'descr': '<f8'"), std::string::npos) << header;
  EXPECT_NE(header.find(", 3), }"), std::string::npos) << header;
}
