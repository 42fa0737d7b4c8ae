/// @file attached_control.cpp
/// See attached_control.h.

#include "attached_control.h"

#include "pixel_loop.h"
#include "qsil/error.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/rng.h"

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

namespace qsil {

int set_attached_control(const PathContext& ctx, CameraAttachment& attachment, int spp) {
  if (spp < 2)
    throw Error("the attached camera hits' control variate needs at least 2 pre-pass spp (got " + std::to_string(spp) +
                ")");
  const Scene& scene = *ctx.scene;
  const Camera& cam = scene.camera;
  const PrimalView view{&scene};
  attachment.control_width = cam.width;
  attachment.control.assign(size_t(cam.width) * size_t(cam.height), Color::Zero());
  std::atomic<int> pixels{0};
  for_each_pixel(cam.width, cam.height, 0, "", [&](int x, int y) {
    const uint64_t pixel = uint64_t(y) * uint64_t(cam.width) + uint64_t(x);
    PathStats st;
    // Camera rays first: a pixel none of whose rays is attached keeps c = 0 and traces no path.
    std::vector<Sampler> samplers;
    std::vector<CameraRay> rays;
    bool touched = false;
    for (int s = 0; s < spp; ++s) {
      samplers.emplace_back(0, pixel, uint64_t(s), stream::kAttachedControl);
      rays.push_back(trace_camera_ray(ctx, x, y, samplers.back().next2(), st));
      const Hit& h = rays.back().hit;
      touched = touched || (h.valid() && attachment.touches(scene, h.shape, h.triangle));
    }
    if (!touched) return;
    // The mean over all of the pixel's samples, attached or not (the variants compared:
    // docs/experiments/2026-11-29-attached-control.md).
    Color sum = Color::Zero(), sum2 = Color::Zero();
    for (int s = 0; s < spp; ++s) {
      const Color L =
          trace_path(ctx, view, {cam.origin(), rays[size_t(s)].dir, rays[size_t(s)].hit}, samplers[size_t(s)], st);
      if (!L.allFinite()) return;
      sum += L;
      sum2 += L * L;
    }
    const Color mean = sum / spp;
    const Color s2 = ((sum2 - sum * mean) / (spp - 1)).max(0.0);
    const Color m2 = mean * mean, denominator = m2 + s2 / spp;
    Color c = Color::Zero();
    for (int k = 0; k < 3; ++k)
      if (denominator[k] > 0) c[k] = mean[k] * m2[k] / denominator[k];
    attachment.control[size_t(pixel)] = c;
    pixels.fetch_add(1);
  });
  return pixels.load();
}

}  // namespace qsil
