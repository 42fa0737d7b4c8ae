#pragma once
/// @file projective_sampling.h
/// The guiding parameters of `--boundary projective` (projective sampling, docs/architecture.md
/// §16; the estimator itself: integrators/projective_boundary.h), apart from it so that
/// configurations (EstimatorConfig, the command line, comparisons) need not include the path
/// tracer.

namespace qsil {

/// What projective sampling's guide is built from (Zhang, Roussel, Jakob 2023 §5; the role of
/// Mitsuba 3's guiding "grid" with guiding_proj false): `resolution` cells per axis of a grid
/// over the boundary segments' unit cube (0, the default: no guiding, Mitsuba 3's "none"),
/// `training` uniform segments per pixel of the image (at least 32 per cell), drawn once at
/// set-up from a fixed stream (so the guide depends on the scene alone), and the uniform
/// density's share of the mixture (> 0: no segment that can contribute gets density 0). Off by
/// default: trained on uniform segments the guide helps through a glossy mirror and hurts under
/// small lights (docs/experiments/2026-11-26-projective-sampling.md §3).
struct ProjectiveGuiding {
  int resolution = 0;
  double training = 4;
  double uniform_share = 0.5;
};

/// Throws qsil::Error ("projective: guiding resolution R out of range [0, 64]", and likewise for
/// training, (0, 1024], and uniform_share, (0, 1]) unless the parameters are in range (with
/// resolution 0 the others are not read).
void check_projective_guiding(const ProjectiveGuiding& guiding);

}  // namespace qsil
