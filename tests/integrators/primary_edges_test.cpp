// The primary boundary term's edges and its sampling distribution (integrators/primary_boundary.h):
// - primary_samples_per_index: the ratio times W x H, rounded up to whole chunks of 1024;
// - every edge's pieces cover [0, 1] of its projected segment in order, at most
//   kPrimaryPieceLength pixels each (up to kPrimaryMaxPieces), with weights the edge's weight times
//   their length, times kPrimaryHiddenShare where hidden; the density integrates to 1;
// - the perspective-correct parameter: the point at s projects to a + s (b - a);
// - the visibility labels are right: of dense points along every edge (brute force, the camera's
//   own visibility ray), at least 99 % of the visible ones lie in pieces labelled visible (Spot
//   seen directly has hidden contour edges, so both labels occur);
// - the hidden share changes the variance, not the mean: the primary term's image sum with the
//   hidden share and with every piece weighed alike (share 1) agree within 3 combined standard
//   errors (fixed seeds), and the share puts fewer samples on hidden edge points.
#include "integrators/light_setup.h"
#include "integrators/primary_boundary.h"
#include "qsil/edgetree/edge_set.h"
#include "qsil/error.h"
#include "qsil/integrators/estimator.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qsil {
namespace {

TEST(PrimarySamples, RatioTimesPixelsRoundedUpToWholeChunks) {
  EXPECT_EQ(primary_samples_per_index(256, 256, 0.25), 16384);
  EXPECT_EQ(primary_samples_per_index(256, 256, 1.0), 65536);
  EXPECT_EQ(primary_samples_per_index(32, 32, 0.25), 1024);    // 256, one chunk
  EXPECT_EQ(primary_samples_per_index(12, 12, 1.0), 1024);     // 144, one chunk
  EXPECT_EQ(primary_samples_per_index(100, 100, 1.0), 10240);  // 10000
  for (double bad : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_THROW(primary_samples_per_index(64, 64, bad), Error);
}

/// Spot seen directly (direct.xml) at 32 x 32, moving sideways, with its primary edges.
struct DirectScene {
  Scene scene = load_scene(test::data_file("scenes/direct.xml"), {{"res", "32"}});
  std::vector<ParameterSpec> params = parse_parameters({"spot:translate:1,0,0"}, scene);
  SceneVelocities vel = compute_velocities(scene, params);
  RayTracer tracer{scene};
  LightSetup lights{scene};
  PathContext ctx = lights.context(scene, tracer);
  edgetree::EdgeSet edges = edgetree::EdgeSet::build(edgetree::forest_inputs(scene));
};

TEST(PrimaryEdges, PiecesCoverEachEdgeWithTheirLengthWeights) {
  const DirectScene d;
  const PrimaryEdges p = find_primary_edges(d.scene, d.edges, d.vel.moving, d.tracer);
  ASSERT_GT(p.edges.size(), 10u);
  ASSERT_EQ(p.cdf.size(), p.pieces.size() + 1);
  EXPECT_GT(p.hidden_pieces, 0) << "Spot has contour edges hidden behind itself";
  EXPECT_LT(p.hidden_pieces, int(p.pieces.size()));
  for (size_t i = 0; i < p.edges.size(); ++i) {
    const PrimaryEdge& pe = p.edges[i];
    const int expected = std::clamp(int(std::ceil(pe.length / kPrimaryPieceLength)), 1, kPrimaryMaxPieces);
    ASSERT_EQ(pe.piece_count, expected) << "edge " << i;
    double s = 0;
    for (int k = pe.first_piece; k < pe.first_piece + pe.piece_count; ++k) {
      const PrimaryPiece& piece = p.pieces[size_t(k)];
      EXPECT_EQ(piece.edge, int(i));
      EXPECT_EQ(piece.s0, s);
      EXPECT_GT(piece.s1, piece.s0);
      const double w = pe.weight * (piece.s1 - piece.s0);
      EXPECT_DOUBLE_EQ(piece.weight, piece.visible ? w : kPrimaryHiddenShare * w);
      EXPECT_NEAR(p.cdf[size_t(k) + 1] - p.cdf[size_t(k)], piece.weight, 1e-13 * p.cdf.back());
      s = piece.s1;
    }
    EXPECT_EQ(s, 1.0) << "edge " << i;
  }
  // The density integrates to 1 over every edge's [0, 1] (midpoint rule per piece is exact: it
  // is constant on each piece).
  double total = 0;
  for (const PrimaryPiece& piece : p.pieces)
    total += p.density(piece.edge, 0.5 * (piece.s0 + piece.s1)) * (piece.s1 - piece.s0);
  EXPECT_NEAR(total, 1.0, 1e-12);
}

TEST(PrimaryEdges, ThePointAtSProjectsToTheFilmPositionAtS) {
  const DirectScene d;
  const PrimaryEdges p = find_primary_edges(d.scene, d.edges, d.vel.moving, d.tracer);
  for (const PrimaryEdge& pe : p.edges)
    for (double s : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0}) {
      const Vec2 film = d.scene.camera.project(pe.point_at(s));
      EXPECT_LT((film - (pe.a + s * (pe.b - pe.a))).norm(), 1e-8 * (1 + pe.length)) << "s " << s;
    }
}

TEST(PrimaryEdges, VisiblePointsLieInPiecesLabelledVisible) {
  const DirectScene d;
  const PrimaryEdges p = find_primary_edges(d.scene, d.edges, d.vel.moving, d.tracer);
  const Vec3 o = d.scene.camera.origin();
  int visible = 0, in_visible_piece = 0, hidden = 0;
  for (const PrimaryEdge& pe : p.edges) {
    IgnoreSet ignore;
    ignore.prims[0] = {pe.edge->shape, pe.edge->f0};
    ignore.prims[1] = {pe.edge->f1 >= 0 ? pe.edge->shape : -1, pe.edge->f1};
    for (int j = 0; j < 64; ++j) {
      const double s = (j + 0.5) / 64;
      const Vec3 to = pe.point_at(s) - o;
      const double dist = to.norm();
      if (d.tracer.occluded(o, to / dist, dist * (1 - 1.0 / 4096), ignore)) {
        ++hidden;
        continue;
      }
      ++visible;
      for (int k = pe.first_piece; k < pe.first_piece + pe.piece_count; ++k) {
        const PrimaryPiece& piece = p.pieces[size_t(k)];
        if (s >= piece.s0 && s <= piece.s1) in_visible_piece += piece.visible;
      }
    }
  }
  std::printf("[ measured ] %d of %d visible dense points in visible pieces; %d dense points hidden\n",
              in_visible_piece, visible, hidden);
  ASSERT_GT(visible, 1000);
  ASSERT_GT(hidden, 1000);
  EXPECT_GE(in_visible_piece, 0.99 * visible);
}

/// The primary term's image sum over a run of `spp` samples per pixel.
ImageSum primary_sum(const DirectScene& d, const PrimaryEdges& p, uint64_t seed, int spp, PathStats& stats) {
  Film film(d.scene.camera.width, d.scene.camera.height, FilmLayout(1));
  // The film counts samples from add_sample only: give every pixel its spp (zero) samples.
  const std::vector<double> zero(size_t(film.channels()), 0.0);
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x)
      for (int s = 0; s < spp; ++s) film.add_sample(x, y, zero.data());
  add_primary_boundary(film, d.ctx, d.vel, p, 1.0, 0, spp, seed, 2, stats);
  return film.derivative_sum(0);
}

TEST(PrimaryEdges, TheHiddenShareChangesTheVarianceNotTheMean) {
  const DirectScene d;
  const PrimaryEdges shared = find_primary_edges(d.scene, d.edges, d.vel.moving, d.tracer);
  const PrimaryEdges plain = find_primary_edges(d.scene, d.edges, d.vel.moving, d.tracer, 1.0);
  PathStats st_shared, st_plain;
  const ImageSum a = primary_sum(d, shared, 31, 256, st_shared), b = primary_sum(d, plain, 32, 256, st_plain);
  std::printf(
      "[ measured ] image sum %.5g +- %.3g (hidden share) vs %.5g +- %.3g (share 1); zero samples %.1f%% vs %.1f%%\n",
      a.sum, a.standard_error, b.sum, b.standard_error,
      100.0 * double(st_shared.boundary_zero) / double(st_shared.boundary_traversals),
      100.0 * double(st_plain.boundary_zero) / double(st_plain.boundary_traversals));
  ASSERT_GT(std::abs(b.sum), 10 * b.standard_error) << "a clearly non-zero primary term";
  EXPECT_NEAR(a.sum, b.sum, 3 * std::hypot(a.standard_error, b.standard_error));
  EXPECT_LT(st_shared.boundary_zero, st_plain.boundary_zero);
}

}  // namespace
}  // namespace qsil
