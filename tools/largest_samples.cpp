/// @file largest_samples.cpp
/// See largest_samples.h.

#include "largest_samples.h"

#include "qsil/error.h"
#include "qsil/files.h"

#include <cstdio>
#include <sstream>

namespace qsil::cli {
namespace {

std::string shape_name(const Scene& scene, int shape) {
  if (shape < 0 || shape >= int(scene.shapes.size())) return "-";
  const std::string& id = scene.shapes[size_t(shape)].id;
  if (!id.empty()) return id;
  std::string name = "#";
  name += std::to_string(shape);
  return name;
}

const char* edge_kind_name(int kind) {
  static const char* const names[] = {"silhouette", "crease", "smoothed crease", "intersection curve"};
  return kind >= 0 && kind < 4 ? names[kind] : "?";
}

}  // namespace

void print_largest_samples(const Scene& scene, const std::vector<ParameterSpec>& params,
                           const std::vector<SampleTrace>& largest) {
  std::printf("largest samples (derivative, mean of the channels; interior = the path retraced without the "
              "boundary term):\n");
  int rank = 0;
  for (const SampleTrace& s : largest) {
    std::printf("  #%d pixel (%d, %d) sample %d, dtheta%d (%s): %.6g = interior %.6g + boundary %.6g\n", ++rank, s.x,
                s.y, s.sample, s.param, s.param < int(params.size()) ? params[size_t(s.param)].text.c_str() : "?",
                s.value, s.interior, s.value - s.interior);
    if (s.camera_emission != 0) std::printf("      emission seen by the camera: %.6g\n", s.camera_emission);
    if (s.camera_jacobian != 0) std::printf("      the attached camera ray's Jacobian term: %.6g\n", s.camera_jacobian);
    for (const VertexTrace& v : s.vertices)
      std::printf(
          "      vertex %d on %s tri %d: |ng.wo| %.3g, ns.wo %.3g, dt %.4g, |dp| %.4g, |dns| %.4g, adds %.6g, arises "
          "%.6g\n",
          v.segments, shape_name(scene, v.shape).c_str(), v.triangle, v.cos_geometric, v.cos_shading, v.dt, v.dp, v.dns,
          v.added, v.arises);
    const BoundaryPointTrace& b = s.boundary;
    if (b.points > 0)
      std::printf("      boundary: %d edge points, sum %.6g; the largest at vertex %d, on a %s of %s: pdf %.4g, rate %g, "
                  "|jump| %.4g, f %.4g, throughput %.4g, g.v %.4g, distance %.4g, edge length %.4g, sin %.3g, adds "
                  "%.6g\n",
                  b.points, b.total, b.segments, edge_kind_name(b.kind), shape_name(scene, b.shape).c_str(), b.pdf,
                  b.rate, b.jump, b.bsdf, b.throughput, b.jacobian, b.distance, b.edge_length, b.sin_view, b.added);
  }
}

void write_largest_samples_csv(const std::string& path, const Scene& scene, const std::vector<SampleTrace>& largest) {
  std::ostringstream out;
  out.precision(9);
  out << "rank,x,y,sample,param,value,interior,boundary,camera_emission,camera_jacobian,segments,shape,triangle,"
         "cos_geometric,cos_shading,dt,dp,dns,added,arises,b_points,b_total,b_segments,b_shape,b_kind,b_pdf,"
         "b_rate,b_jump,b_bsdf,b_throughput,b_jacobian,b_distance,b_edge_length,b_sin_view,b_added\n";
  int rank = 0;
  for (const SampleTrace& s : largest) {
    ++rank;
    const auto head = [&] {
      out << rank << ',' << s.x << ',' << s.y << ',' << s.sample << ',' << s.param << ',' << s.value << ','
          << s.interior << ',' << s.value - s.interior << ',' << s.camera_emission << ',' << s.camera_jacobian << ',';
    };
    const BoundaryPointTrace& b = s.boundary;
    const auto tail = [&] {
      out << ',' << b.points << ',' << b.total;
      if (b.points > 0)
        out << ',' << b.segments << ',' << shape_name(scene, b.shape) << ',' << b.kind << ',' << b.pdf << ','
            << b.rate << ',' << b.jump << ',' << b.bsdf << ',' << b.throughput << ',' << b.jacobian << ','
            << b.distance << ',' << b.edge_length << ',' << b.sin_view << ',' << b.added;
      else
        out << ",,,,,,,,,,,,,";
      out << '\n';
    };
    if (s.vertices.empty()) {
      head();
      out << ",,,,,,,,,";
      tail();
    }
    for (const VertexTrace& v : s.vertices) {
      head();
      out << v.segments << ',' << shape_name(scene, v.shape) << ',' << v.triangle << ',' << v.cos_geometric << ','
          << v.cos_shading << ',' << v.dt << ',' << v.dp << ',' << v.dns << ',' << v.added << ',' << v.arises;
      tail();
    }
  }
  write_file(path, out.str());
}

}  // namespace qsil::cli
