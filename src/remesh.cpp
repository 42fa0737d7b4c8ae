/// @file remesh.cpp
/// See qsil/remesh.h. The one file of the core that includes CGAL (compiled on its own, as
/// edgetree/intersection_curves.cpp is: CGAL's flags stay out of the renderer's code).

#include "qsil/remesh.h"

#include "qsil/error.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <cmath>
#include <string>
#include <vector>

namespace qsil {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;
}  // namespace

TriangleMesh isotropic_remesh(const TriangleMesh& mesh, double target_edge_length, int iterations) {
  if (!(target_edge_length > 0) || !std::isfinite(target_edge_length))
    throw Error("isotropic_remesh: target edge length " + std::to_string(target_edge_length) +
                " is not a positive finite number");
  if (iterations < 1) throw Error("isotropic_remesh: iterations " + std::to_string(iterations) + " < 1");
  if (mesh.triangles.empty()) throw Error("isotropic_remesh: the mesh has no triangle");
  std::vector<Point> points;
  points.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= mesh.num_vertices())
        throw Error("isotropic_remesh: a triangle refers to vertex " + std::to_string(t[k]) + " of " +
                    std::to_string(mesh.num_vertices()));
    polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  }
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    throw Error("isotropic_remesh: the triangles are not a manifold, consistently oriented mesh");
  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  PMP::isotropic_remeshing(faces(sm), target_edge_length, sm, CGAL::parameters::number_of_iterations(iterations));
  sm.collect_garbage();
  TriangleMesh out;
  out.positions.reserve(sm.number_of_vertices());
  for (SurfaceMesh::Vertex_index v : sm.vertices()) {
    const Point& p = sm.point(v);
    out.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (SurfaceMesh::Face_index f : sm.faces()) {
    Eigen::Vector3i t;
    int k = 0;
    for (SurfaceMesh::Vertex_index v : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = int(v.idx());
    out.triangles.push_back(t);
  }
  return out;
}

}  // namespace qsil
