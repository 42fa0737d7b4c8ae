#pragma once
/// @file attached_control.h
/// The control variate of attached camera hits (CameraAttachment::control): a per-pixel constant c
/// from a primal pre-pass, which the warp's Jacobian term and the attached flux take from L.
/// Measurements: docs/experiments/2026-11-28-jacobian-control-variate.md (the choice of c) and
/// docs/experiments/2026-11-29-attached-control.md (as built).

#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/path_tracer.h"

namespace qsil {

/// Fills `attachment.control` (CameraAttachment) for `ctx.scene`'s camera: at every pixel where one
/// of `spp` (>= 2) pre-pass camera rays hits a triangle the attachment touches, c is the pre-pass
/// mean of the primal radiance shrunk towards 0 by its own noise, per channel:
/// c = mean mean² / (mean² + s² / spp), s² the samples' unbiased variance (James-Stein-like: a c
/// as noisy as the pixel's spread adds more variance than it removes); elsewhere, and where a
/// sample is not finite, c = 0. The pre-pass is a fixed function of the scene (seed 0, a stream of
/// its own, stream::kAttachedControl), so c is fixed before any run, as unbiasedness requires. Runs
/// on every core of the current arena. Returns the number of pixels given a control (whose c may
/// still be 0 in a channel). Throws qsil::Error when spp < 2.
int set_attached_control(const PathContext& ctx, CameraAttachment& attachment, int spp);

}  // namespace qsil
