// Runs split into parts (qsil/integrators/distributed.h), without MPI: the parts of a run, combined
// in order with merge_part, equal the whole run bit for bit — every sum, squared sum, splat sum
// and count of the film, and every counter — for any number of parts and threads, for the primal
// image, the gradient with and without a boundary term (primary splats included; projective
// sampling's boundary segments too, guided or not) and finite
// differences. A distributed run transports exactly these films (tests/mpi_cli_test.cpp checks
// the program under mpirun).
#include "qsil/integrators/distributed.h"
#include "qsil/error.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cstring>

namespace qsil {
namespace {

Scene shadow_quad(int res) {
  return load_scene(test::data_file("scenes/shadow-quad.xml"),
                    {{"res", std::to_string(res)}, {"spp", "4"}, {"max_depth", "2"}});
}

RenderOptions options(int first, int spp, int threads) {
  RenderOptions o;
  o.first_sample = first;
  o.spp = spp;
  o.seed = 11;
  o.threads = threads;
  o.progress = false;
  return o;
}

/// The films' states are the same bits (so are every mean and standard error derived from them).
void expect_bit_identical(const RenderResult& a, const RenderResult& b, const std::string& what) {
  const std::vector<double> sa = a.film.state(), sb = b.film.state();
  ASSERT_EQ(sa.size(), sb.size()) << what;
  size_t differ = 0;
  for (size_t i = 0; i < sa.size(); ++i) differ += std::memcmp(&sa[i], &sb[i], sizeof(double)) != 0;
  EXPECT_EQ(differ, 0u) << what << ": " << differ << " of " << sa.size() << " film values differ";
  EXPECT_EQ(a.rays, b.rays) << what;
  EXPECT_EQ(a.traversals, b.traversals) << what;
  EXPECT_EQ(a.zero_traversals, b.zero_traversals) << what;
  EXPECT_EQ(a.nonfinite, b.nonfinite) << what;
  EXPECT_EQ(a.spp, b.spp) << what;
  EXPECT_EQ(a.first_sample, b.first_sample) << what;
}

/// For 1 to 5 parts (on 1 or 2 threads), the combined parts equal the whole run (2 threads).
void expect_parts_combine_to_whole(const Estimator& e, const RenderOptions& o, const std::string& what) {
  RenderOptions whole_options = o;
  whole_options.threads = 2;
  const RenderResult whole = e.run(whole_options);
  for (int parts = 1; parts <= 5; ++parts) {
    RenderOptions po = o;
    po.threads = 1 + parts % 2;
    expect_bit_identical(run_in_parts(e, po, parts), whole, what + ", " + std::to_string(parts) + " parts");
  }
}

TEST(Distributed, PartsCombineToTheWholeRunBitForBit) {
  // 12 x 12 = 144 pixels (not a multiple of the primary term's 1024-sample chunks) and a range
  // that starts inside a chunk; 32 x 32 from 0.
  for (int res : {12, 32}) {
    const Scene scene = shadow_quad(res);
    const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
    const RenderOptions o = res == 12 ? options(3, 5, 1) : options(0, 4, 1);
    const std::string at = std::to_string(res) + "^2";
    expect_parts_combine_to_whole(Estimator(scene, EstimatorConfig::primal()), o, "primal " + at);
    expect_parts_combine_to_whole(Estimator(scene, EstimatorConfig::gradient(params, Method::Quadric)), o,
                                  "quadric " + at);
    expect_parts_combine_to_whole(Estimator(scene, EstimatorConfig::gradient(params, Method::None)), o,
                                  "interior " + at);
    expect_parts_combine_to_whole(Estimator(scene, EstimatorConfig::gradient(params, Method::Projective)), o,
                                  "projective " + at);
    EstimatorConfig guided = EstimatorConfig::gradient(params, Method::Projective);
    guided.projective_guiding.resolution = 16;  // trained once at set-up: the same guide in every part
    expect_parts_combine_to_whole(Estimator(scene, guided), o, "projective, guided " + at);
    EstimatorConfig octree = EstimatorConfig::gradient(params, Method::Projective);
    octree.projective_guiding.octree = true;  // its seeds drawn once at set-up too
    expect_parts_combine_to_whole(Estimator(scene, octree), o, "projective, octree guide " + at);
    expect_parts_combine_to_whole(Estimator(scene, EstimatorConfig::finite_differences(params)), o, "fd " + at);
  }
}

TEST(Distributed, EachPartRendersOnlyItsPixelsAndItsShareOfThePrimaryTerm) {
  // 32 x 32 x 4 spp: four chunks of 1024 primary samples, shared 1, 1, 2 by three parts.
  const Scene scene = shadow_quad(32);
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
  const Estimator e(scene, EstimatorConfig::gradient(params, Method::Quadric));
  const RenderResult whole = e.run(options(0, 4, 2));
  ASSERT_TRUE(whole.splats.empty());  // a whole run adds its splats to its film
  const int parts = 3;
  size_t splats = 0;
  uint64_t rays = 0;
  for (int part = 0; part < parts; ++part) {
    RenderOptions o = options(0, 4, 2);
    o.part = part;
    o.parts = parts;
    const RenderResult r = e.run(o);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x)
        ASSERT_EQ(r.film.samples(x, y), Film::part_of(y * 32 + x, parts) == part ? 4 : 0) << x << "," << y;
    EXPECT_GT(r.splats.size(), 0u) << part;
    EXPECT_LT(r.rays, whole.rays) << part;
    splats += r.splats.size();
    rays += r.rays;
  }
  EXPECT_EQ(rays, whole.rays);  // the parts share the work, nothing is done twice
  EXPECT_GT(splats, 0u);
}

TEST(Distributed, SummingPartialFilmsWouldNotBeBitIdentical) {
  // Why merge_part passes one film along the parts: adding per-part partial sums in another order
  // changes the last bits of the splat sums (floating-point addition is not associative).
  const Scene scene = shadow_quad(32);
  const std::vector<ParameterSpec> params{parse_parameter("object:translate:1,0,0", scene)};
  const Estimator e(scene, EstimatorConfig::gradient(params, Method::Quadric));
  const RenderResult whole = e.run(options(0, 8, 2));
  RenderResult summed;
  summed.film = Film(32, 32, e.layout(), whole.film.stratum_fraction());
  for (int part = 0; part < 2; ++part) {
    RenderOptions o = options(0, 8, 2);
    o.part = part;
    o.parts = 2;
    const RenderResult r = e.run(o);
    Film partial(32, 32, e.layout(), r.film.stratum_fraction());
    partial.copy_part(r.film, part, 2);
    for (const FilmSplat& s : r.splats) partial.splat(s.x, s.y, s.channel, s.value);
    summed.film.merge(partial);
  }
  const std::vector<double> a = whole.film.state(), b = summed.film.state();
  size_t differ = 0;
  for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
  EXPECT_GT(differ, 0u);
}

TEST(Distributed, RejectsBadParts) {
  const Scene scene = shadow_quad(8);
  const Estimator e(scene, EstimatorConfig::primal());
  RenderOptions o = options(0, 1, 1);
  o.parts = 2;
  o.part = 2;
  EXPECT_THROW(e.run(o), Error);
  o.part = -1;
  EXPECT_THROW(e.run(o), Error);
  o.part = 0;
  o.parts = 0;
  EXPECT_THROW(e.run(o), Error);
  EXPECT_THROW(run_in_parts(e, options(0, 1, 1), 0), Error);
}

TEST(Distributed, AGroupOfOneProcessRunsTheEstimatorAndReportsErrorsAsGroupErrors) {
  const ProcessGroup group;
  EXPECT_EQ(group.size(), 1);
  EXPECT_TRUE(group.root());
  const Scene scene = shadow_quad(8);
  const Estimator e(scene, EstimatorConfig::primal());
  expect_bit_identical(group.run(e, options(0, 2, 1)), e.run(options(0, 2, 2)), "group of one");
  EXPECT_EQ(group.sum(7), 7u);
  EXPECT_NO_THROW(group.agree());
  try {
    group.all_or_none([] { throw Error("scene.xml:3: bad"); });
    ADD_FAILURE() << "no GroupError";
  } catch (const GroupError& g) {
    EXPECT_STREQ(g.what(), "scene.xml:3: bad");
    EXPECT_EQ(g.exit_code(), 2);
  }
  try {
    group.all_or_none([] { throw std::runtime_error("oops"); });
    ADD_FAILURE() << "no GroupError";
  } catch (const GroupError& g) {
    EXPECT_STREQ(g.what(), "internal error: oops");
    EXPECT_EQ(g.exit_code(), 1);
  }
}

}  // namespace
}  // namespace qsil
