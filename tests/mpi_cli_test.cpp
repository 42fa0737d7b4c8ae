// The `qsil` program under `mpirun` (built and registered only when CMake found MPI, Open MPI's
// mpirun: tests/CMakeLists.txt). `render`, `grad`, `fd` and `reference` on 2 and 3 ranks (1
// thread each, oversubscribed) write EXRs whose pixels are bit-identical to one process on 2
// threads; a rank with bad input, a killed rank and a failed write end the job with one line on
// stderr, a non-zero exit code and no output file.
#include "qsil/image.h"
#include "shell_run.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

namespace {

using qsil::testing::ShellRun;

/// Runs the shell command `cmd` from the repository root, capturing stdout and stderr.
ShellRun run_shell(const std::string& cmd) { return qsil::testing::run_shell(cmd, "qsil_mpi_test"); }

/// `mpirun -np RANKS` of the shell words `command` (root allowed: CI runs as root; no single-copy
/// shared memory, which containers may forbid; -q: mpirun's own reports off, so that stderr holds
/// qsil's lines only).
std::string mpirun(int ranks, const std::string& command) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none " +
         std::string(QSIL_MPIEXEC) + " -q --oversubscribe --bind-to none -np " + std::to_string(ranks) + " " + command;
}

std::string qsil() { return QSIL_CLI_PATH; }

std::string tmp(const std::string& name) {
  return (std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "_mpi_" + name)).string();
}

/// Same channels, same pixel bits.
void expect_same_pixels(const std::string& a, const std::string& b) {
  const qsil::Image ia = qsil::read_exr(a), ib = qsil::read_exr(b);
  ASSERT_EQ(ia.width, ib.width);
  ASSERT_EQ(ia.height, ib.height);
  ASSERT_EQ(ia.channel_names, ib.channel_names);
  for (size_t c = 0; c < ia.planes.size(); ++c) {
    size_t differ = 0;
    for (size_t i = 0; i < ia.planes[c].size(); ++i)
      differ += std::memcmp(&ia.planes[c][i], &ib.planes[c][i], sizeof(float)) != 0;
    EXPECT_EQ(differ, 0u) << b << " vs " << a << ": channel " << ia.channel_names[c];
  }
}

/// `qsil ARGS` in one process (2 threads) and under mpirun on 2 and 3 ranks (1 thread each): the
/// same pixels; rank 0 alone prints the summary, and the same warnings as one process (a dominant
/// pixel's, the only kind these runs may print: the film is the same).
void expect_ranks_agree(const std::string& name, const std::string& args) {
  const std::string one = tmp(name + "_1.exr");
  const ShellRun r1 = run_shell(qsil() + " " + args + " -q --threads 2 -o " + one);
  ASSERT_EQ(r1.code, 0) << r1.err;
  for (size_t at = 0, end; at < r1.err.size(); at = end + 1) {
    end = r1.err.find('\n', at);
    ASSERT_NE(end, std::string::npos) << r1.err;
    EXPECT_NE(r1.err.substr(at, end - at).find(": warning: dtheta"), std::string::npos) << r1.err;
  }
  for (int ranks : {2, 3}) {
    const std::string many = tmp(name + "_" + std::to_string(ranks) + ".exr");
    std::filesystem::remove(many);
    const ShellRun r = run_shell(mpirun(ranks, qsil() + " " + args + " -q --threads 1 -o " + many));
    ASSERT_EQ(r.code, 0) << ranks << " ranks: " << r.err;
    EXPECT_EQ(r.err, r1.err) << ranks << " ranks";
    // One summary line (rank 0), naming the processes.
    const std::string note = std::to_string(ranks) + " processes";
    EXPECT_NE(r.out.find(note), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find(note), r.out.rfind(note)) << r.out;
    expect_same_pixels(one, many);
    EXPECT_EQ(qsil::read_exr(many).attributes.at("qsil:processes"), std::to_string(ranks));
  }
}

TEST(MPI, RenderIsBitIdenticalOnOneTwoAndThreeRanks) {
  expect_ranks_agree("render", "render scenes/shadow-quad.xml -D res=32 --spp 8 --seed 3");
}

TEST(MPI, GradIsBitIdenticalOnOneTwoAndThreeRanks) {
  // shadow-quad: secondary edges (the shadow) and primary ones; direct: Spot's primary silhouette.
  expect_ranks_agree("grad_quad",
                     "grad scenes/shadow-quad.xml -D res=32 --spp 4 --seed 4 --param object:translate:1,0,0");
  expect_ranks_agree("grad_direct", "grad scenes/direct.xml -D res=32 --spp 2 --seed 4 --param spot:translate:0,1,0");
}

TEST(MPI, FdAndReferenceAreBitIdenticalOnOneTwoAndThreeRanks) {
  expect_ranks_agree("fd", "fd scenes/spot-mirror.xml -D res=32 --spp 4 --seed 5 --param spot:translate:0,1,0");
  // The reference's .se channels: the squared sums are the one-process ones too.
  expect_ranks_agree("reference",
                     "reference scenes/shadow-quad.xml -D res=32 --spp 4 --seed 6 --param object:translate:1,0,0 "
                     "--method quadric");
}

/// One line on stderr containing `needle`, exit code `code`, no `output`.
void expect_one_line_error(const ShellRun& r, int code, const std::string& needle, const std::string& output) {
  EXPECT_EQ(r.code, code) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(output)) << output;
}

TEST(MPI, BadInputOnOneRankEndsTheJobWithOneLineAndNoOutput) {
  const std::string out = tmp("bad_rank.exr");
  std::filesystem::remove(out);
  // Rank 1 (only) is given a scene that does not exist.
  const std::string cmd =
      "sh -c 'if [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then s=scenes/does_not_exist.xml; else "
      "s=scenes/shadow-quad.xml; fi; exec " +
      qsil() + " render $s -D res=16 --spp 2 -q -o " + out + "'";
  expect_one_line_error(run_shell(mpirun(2, cmd)), 2, "qsil: rank 1: scenes/does_not_exist.xml", out);
  // Bad input on every rank: one line, as in one process.
  expect_one_line_error(run_shell(mpirun(3, qsil() +
                                                " grad scenes/shadow-quad.xml --param nosuch:translate:0,1,0 "
                                                "-D res=16 --spp 1 -q -o " +
                                                out)),
                        2, "no shape with id 'nosuch'", out);
}

TEST(MPI, AFailedWriteOnRankZeroEndsEveryRankWithOneLine) {
  const std::string out = tmp("no_such_dir") + "/out.exr";
  expect_one_line_error(run_shell(mpirun(2, qsil() + " render scenes/shadow-quad.xml -D res=16 --spp 1 -q -o " + out)),
                        2, "qsil: ", out);
}

TEST(MPI, AKilledRankEndsTheJobWithoutOutput) {
  const std::string out = tmp("killed.exr");
  std::filesystem::remove(out);
  // Rank 1 is killed after a second of a render that takes minutes on one thread.
  const std::string cmd = "sh -c 'if [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then (sleep 1; kill -9 $$) & fi; exec " +
                          qsil() + " render scenes/spot-mirror.xml -D res=128 --spp 2048 --threads 1 -q -o " + out +
                          "'";
  const ShellRun r = run_shell(mpirun(2, cmd));
  EXPECT_NE(r.code, 0);
  EXPECT_LT(r.seconds, 60);
  EXPECT_FALSE(std::filesystem::exists(out));
  // Rank 0, ended by the launcher, says why in one line.
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("ended by the MPI launcher"), std::string::npos) << r.err;
}

TEST(MPI, CommandsThatDoNotSplitRefuseToRunUnderMpirun) {
  const ShellRun r = run_shell(mpirun(2, qsil() + " forest scenes/shadow-quad.xml --stats"));
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("does not run under an MPI launcher"), std::string::npos) << r.err;
}

}  // namespace
