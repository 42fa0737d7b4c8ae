#pragma once
/// @file remesh.h
/// Isotropic remeshing of a triangle mesh, for shape optimisation (Nicolet et al. 2021 remesh at a
/// schedule of shrinking target edge lengths): CGAL's Polygon Mesh Processing
/// `isotropic_remeshing` (Botsch and Kobbelt 2004: split long edges, collapse short ones, flip
/// toward valence 6, tangential relaxation, projection back onto the input), on a copy.

#include "qsil/scene.h"

namespace qsil {

/// The mesh remeshed toward edges of length `target_edge_length` (scene units) in `iterations`
/// rounds. The input must be a consistently oriented, manifold triangle mesh (open or closed);
/// the output keeps its orientation and border, with positions and triangles only (the caller
/// recomputes normals, as Scene::set_mesh-style code does). Throws qsil::Error for a target that
/// is not a positive finite number, iterations < 1, an input with no triangle or one CGAL cannot
/// hold as a polygon mesh (non-manifold, inconsistent orientation), naming the reason.
TriangleMesh isotropic_remesh(const TriangleMesh& mesh, double target_edge_length, int iterations = 3);

}  // namespace qsil
