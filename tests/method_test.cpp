// The one method type (qsil/method.h): every name parses back to its method, the subsets accept
// exactly their members with an error that lists them, and the structure predicates agree with
// what each method samples from.
#include "qsil/integrators/method.h"
#include "qsil/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>

namespace qsil {
namespace {

TEST(Method, NamesRoundTrip) {
  std::set<std::string> names;
  for (Method m : kAllMethods) {
    const std::string name(method_name(m));
    EXPECT_EQ(parse_method(name, "--methods", kAllMethods), m) << name;
    names.insert(name);
  }
  EXPECT_EQ(names.size(), kAllMethods.size());  // distinct names
  EXPECT_EQ(method_name(Method::QuadricBox), "quadric-box");
  EXPECT_EQ(method_name(Method::FiniteDifferences), "fd");
}

TEST(Method, SubsetsRejectOtherMethodsNamingTheOptionAndTheChoices) {
  try {
    parse_method("fd", "--boundary", kBoundaryMethods);
    FAIL() << "fd is not a --boundary method";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "--boundary 'fd': unsupported (supported: quadric, quadric-box, vsphere, vsphere-solid, uniform, none, "
              "regularized, was, projective)");
  }
  EXPECT_THROW(parse_method("none", "--method", kReferenceMethods), Error);
  EXPECT_THROW(parse_method("Quadric", "--methods", kAllMethods), Error);  // case matters
  EXPECT_THROW(parse_method("", "--methods", kAllMethods), Error);
  EXPECT_EQ(parse_method("fd", "--method", kReferenceMethods), Method::FiniteDifferences);
}

TEST(Method, StructurePredicates) {
  for (Method m : kAllMethods) {
    const bool in_edge =
        std::find(kEdgeSamplingMethods.begin(), kEdgeSamplingMethods.end(), m) != kEdgeSamplingMethods.end();
    EXPECT_EQ(samples_edges(m), in_edge) << method_name(m);
    EXPECT_LE(uses_quadrics(m), uses_edge_forest(m)) << method_name(m);  // quadrics need a forest
    EXPECT_LE(uses_edge_forest(m), samples_edges(m)) << method_name(m);
    EXPECT_LE(samples_edges(m), uses_edge_set(m)) << method_name(m);  // every edge sampler reads the edge set
  }
  EXPECT_TRUE(uses_quadrics(Method::Quadric));
  EXPECT_FALSE(uses_quadrics(Method::QuadricBox));
  EXPECT_TRUE(uses_edge_forest(Method::QuadricBox));
  for (Method m : {Method::VSphere, Method::VSphereSolid, Method::Uniform}) EXPECT_FALSE(uses_edge_forest(m));
  EXPECT_TRUE(uses_edge_set(Method::Projective));
  EXPECT_FALSE(samples_edges(Method::Projective));
  // The rejection methods are the first four, in display order.
  for (size_t i = 0; i < kRejectionMethods.size(); ++i) EXPECT_EQ(kRejectionMethods[i], kAllMethods[i]);
}

}  // namespace
}  // namespace qsil
