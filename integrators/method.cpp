/// @file method.cpp
/// Method names and defaults; see qsil/integrators/method.h.

#include "qsil/integrators/method.h"

#include "qsil/check.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/edgetree/vsphere_tree.h"
#include "qsil/error.h"

#include <algorithm>

namespace qsil {

std::string_view method_name(Method method) {
  switch (method) {
    case Method::Quadric: return "quadric";
    case Method::QuadricBox: return "quadric-box";
    case Method::VSphere: return "vsphere";
    case Method::VSphereSolid: return "vsphere-solid";
    case Method::Uniform: return "uniform";
    case Method::None: return "none";
    case Method::Regularized: return "regularized";
    case Method::WarpedArea: return "was";
    case Method::Projective: return "projective";
    case Method::FiniteDifferences: return "fd";
  }
  return "?";
}

std::string method_list(std::span<const Method> allowed) {
  std::string out;
  for (Method m : allowed) out += (out.empty() ? "" : ", ") + std::string(method_name(m));
  return out;
}

Method parse_method(std::string_view name, std::string_view option, std::span<const Method> allowed) {
  const auto it = std::find_if(allowed.begin(), allowed.end(), [&](Method m) { return method_name(m) == name; });
  if (it != allowed.end()) return *it;
  throw Error(std::string(option) + " '" + std::string(name) + "': unsupported (supported: " + method_list(allowed) +
              ")");
}

bool samples_edges(Method method) {
  return std::find(kEdgeSamplingMethods.begin(), kEdgeSamplingMethods.end(), method) != kEdgeSamplingMethods.end();
}

bool uses_edge_set(Method method) { return samples_edges(method) || method == Method::Projective; }

bool uses_edge_forest(Method method) { return method == Method::Quadric || method == Method::QuadricBox; }

bool uses_quadrics(Method method) { return method == Method::Quadric; }

double default_sppi(Method method) { return uses_edge_forest(method) ? 0.5 : 1.0; }

double default_split_speed(Method method) { return uses_edge_forest(method) ? 4.0 : 0.0; }

edgetree::NodeTest node_test(Method method) {
  QSIL_CHECK(uses_edge_forest(method));
  return method == Method::Quadric ? edgetree::NodeTest::DualBoxAndQuadrics : edgetree::NodeTest::DualBox;
}

edgetree::VSphereTest vsphere_test(Method method) {
  QSIL_CHECK(method == Method::VSphere || method == Method::VSphereSolid);
  return method == Method::VSphere ? edgetree::VSphereTest::Hollow : edgetree::VSphereTest::Solid;
}

}  // namespace qsil
