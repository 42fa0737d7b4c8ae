#pragma once
/// @file projective_sampling.h
/// The guiding parameters of `--boundary projective` (projective sampling, docs/architecture.md
/// §16; the estimator itself: integrators/projective_boundary.h), apart from it so that
/// configurations (EstimatorConfig, the command line, comparisons) need not include the path
/// tracer.

namespace qsil {

/// What projective sampling's guide is built from (Zhang, Roussel, Jakob 2023 §5), one of:
/// - none (the default: resolution 0, octree false; Mitsuba 3's guiding "none");
/// - a grid (Mitsuba 3's guiding "grid" with guiding_proj false): `resolution` cells per axis over
///   the boundary segments' unit cube, from `training` uniform segments per pixel of the image (at
///   least 32 per cell), drawn once at set-up from a fixed stream (so the guide depends on the
///   scene alone);
/// - an octree from projected seeds (`octree`; Mitsuba 3's guiding "octree" with guiding_proj
///   true): `seeds` camera paths per pixel (Mitsuba 3's proj_seed_spp), their segments projected
///   onto nearby silhouettes (silhouette_projection.h), drawn once at set-up from a fixed stream.
/// `uniform_share` is the uniform density's share of either mixture (> 0: no segment that can
/// contribute gets density 0). Off by default: docs/experiments/2026-11-26-projective-sampling.md
/// §3 (grid) and §4 (octree) measure where each guide helps and hurts.
struct ProjectiveGuiding {
  int resolution = 0;
  double training = 4;
  double uniform_share = 0.5;
  bool octree = false;
  double seeds = 64;
};

/// Throws qsil::Error ("projective: guiding resolution R out of range [0, 64]", and likewise for
/// training, (0, 1024], seeds, (0, 1024], and uniform_share, (0, 1]; "projective: a guiding
/// resolution and the octree guide exclude each other") unless the parameters are valid (without
/// a guide the others are not read).
void check_projective_guiding(const ProjectiveGuiding& guiding);

}  // namespace qsil
