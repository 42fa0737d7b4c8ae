#pragma once
/// @file largest_samples.h
/// `qsil grad --largest-samples K [--largest-samples-csv FILE]`: the report of a run's largest
/// samples and their paths (qsil/integrators/sample_trace.h).

#include "qsil/integrators/sample_trace.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <string>
#include <vector>

namespace qsil::cli {

/// Prints `largest` (largest first) to stdout: per sample its pixel, sample index, parameter,
/// derivative (channel mean), interior and secondary boundary parts, then one line per path
/// vertex (segments before it, shape id, triangle, |n_g . wo|, n_s . wo, dt/dtheta, |dp/dtheta|,
/// |dn_s/dtheta|, the derivative added from that vertex on, and the part of the interior term that
/// arises there, VertexTrace::arises; with an attached camera ray, a line with its Jacobian term
/// before them), and a line on its secondary boundary
/// term's largest edge point (BoundaryPointTrace: vertex, edge kind and shape, pdf, jump, BSDF,
/// throughput, g . v, distance, edge length, sin of the view angle, contribution).
void print_largest_samples(const Scene& scene, const std::vector<ParameterSpec>& params,
                           const std::vector<SampleTrace>& largest);

/// Writes the same as CSV to `path`, one row per vertex (a sample without vertices: one row with
/// empty vertex columns), each row ending with the sample's b_* columns (BoundaryPointTrace;
/// empty but b_points and b_total without edge points); whole or absent: throws qsil::Error naming the file when it cannot be
/// written.
void write_largest_samples_csv(const std::string& path, const Scene& scene, const std::vector<SampleTrace>& largest);

}  // namespace qsil::cli
