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
    for (const VertexTrace& v : s.vertices)
      std::printf("      vertex %d on %s tri %d: |ng.wo| %.3g, ns.wo %.3g, dt %.4g, |dp| %.4g, |dns| %.4g, adds %.6g\n",
                  v.segments, shape_name(scene, v.shape).c_str(), v.triangle, v.cos_geometric, v.cos_shading, v.dt, v.dp,
                  v.dns, v.added);
  }
}

void write_largest_samples_csv(const std::string& path, const Scene& scene, const std::vector<SampleTrace>& largest) {
  std::ostringstream out;
  out.precision(9);
  out << "rank,x,y,sample,param,value,interior,boundary,camera_emission,segments,shape,triangle,cos_geometric,"
         "cos_shading,dt,dp,dns,added\n";
  int rank = 0;
  for (const SampleTrace& s : largest) {
    ++rank;
    const auto head = [&] {
      out << rank << ',' << s.x << ',' << s.y << ',' << s.sample << ',' << s.param << ',' << s.value << ','
          << s.interior << ',' << s.value - s.interior << ',' << s.camera_emission << ',';
    };
    if (s.vertices.empty()) {
      head();
      out << ",,,,,,,,\n";
    }
    for (const VertexTrace& v : s.vertices) {
      head();
      out << v.segments << ',' << shape_name(scene, v.shape) << ',' << v.triangle << ',' << v.cos_geometric << ','
          << v.cos_shading << ',' << v.dt << ',' << v.dp << ',' << v.dns << ',' << v.added << '\n';
    }
  }
  write_file(path, out.str());
}

}  // namespace qsil::cli
