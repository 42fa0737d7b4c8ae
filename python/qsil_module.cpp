/// @file qsil_module.cpp
/// The Python module `qsil` (pybind11 and NumPy from Debian; built by CMake beside the library,
/// <build>/python/qsil*.so; docs/architecture.md §13): load a scene, read and set vertex
/// positions, render, forward-mode derivative images and reverse-mode per-vertex gradients, as
/// NumPy arrays. Images are (height, width, 3) float64 arrays, row 0 the top of the picture.
/// Every qsil::Error becomes `qsil.Error` (a ValueError) with the one-line message; rendering
/// releases the GIL.

#include "qsil/error.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/reverse.h"
#include "qsil/integrators/method.h"
#include "qsil/parameters.h"
#include "qsil/remesh.h"
#include "qsil/scene.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <mutex>
#include <optional>

namespace py = pybind11;

namespace qsil {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// The index of shape `id`; throws qsil::Error naming it when the scene has none.
int shape_index(const Scene& scene, const std::string& id) {
  const int s = scene.find_shape(id);
  if (s < 0) throw Error("shape '" + id + "': no shape with this id in " + scene.file.string());
  return s;
}

/// Render options from the keyword arguments (spp <= 0: the scene's sample count).
RenderOptions options(int spp, uint64_t seed, int threads) {
  RenderOptions o;
  o.spp = spp;
  o.seed = seed;
  o.threads = threads;
  o.progress = false;
  return o;
}

/// Channel `channel(c)` of a film's pixel means as an (H, W, 3) array.
template <class Channel>
Array film_image(const Film& film, Channel&& channel) {
  Array out({film.height(), film.width(), 3});
  auto m = out.mutable_unchecked<3>();
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x)
      for (int c = 0; c < 3; ++c) m(y, x, c) = film.mean(channel(c), x, y);
  return out;
}

/// The rows of a (V, 3) array as positions; throws qsil::Error "<where>vertex i is non-finite or
/// beyond 1e12 scene units" for the first that is (kMaxCoordinate, as the OBJ loader refuses).
std::vector<Vec3> checked_positions(const Array& v, const std::string& where) {
  auto a = v.unchecked<2>();
  std::vector<Vec3> pos(size_t(v.shape(0)));
  for (py::ssize_t i = 0; i < v.shape(0); ++i) {
    pos[size_t(i)] = Vec3(a(i, 0), a(i, 1), a(i, 2));
    if (!pos[size_t(i)].allFinite() || pos[size_t(i)].cwiseAbs().maxCoeff() > kMaxCoordinate)
      throw Error(where + "vertex " + std::to_string(i) + " is non-finite or beyond 1e12 scene units");
  }
  return pos;
}

/// Sets shape `id`'s vertex positions from a (V, 3) array and recomputes its area-weighted vertex
/// normals (unless it uses face normals), as a displaced scene does. Throws qsil::Error for a
/// wrong shape or a non-finite or too large coordinate.
void set_vertices(Scene& scene, const std::string& id, const Array& v) {
  Shape& shape = scene.shapes[size_t(shape_index(scene, id))];
  TriangleMesh& mesh = shape.mesh;
  if (v.ndim() != 2 || v.shape(1) != 3 || v.shape(0) != mesh.num_vertices())
    throw Error("set_vertices('" + id + "'): expected an array of shape (" + std::to_string(mesh.num_vertices()) +
                ", 3)");
  mesh.positions = checked_positions(v, "set_vertices('" + id + "'): ");
  if (!shape.face_normals) mesh.normals = vertex_normals(mesh);
}

/// Replaces shape `id`'s mesh by vertex positions (V, 3) and triangles (T, 3) (vertex indices,
/// counter-clockwise = outward), recomputing its area-weighted vertex normals (unless it uses face
/// normals): what an optimiser does after a remeshing. Throws qsil::Error, naming the shape and
/// the first offending row, for a wrong array shape, a non-finite or too large coordinate, an index
/// out of range, or a triangle of zero area (no edge structure can hold it); nothing changes then.
void set_mesh(Scene& scene, const std::string& id, const Array& v, const py::array_t<long long>& f) {
  Shape& shape = scene.shapes[size_t(shape_index(scene, id))];
  const std::string where = "set_mesh('" + id + "'): ";
  if (v.ndim() != 2 || v.shape(1) != 3 || v.shape(0) < 3)
    throw Error(where + "expected positions of shape (V, 3) with V >= 3");
  if (f.ndim() != 2 || f.shape(1) != 3 || f.shape(0) < 1)
    throw Error(where + "expected triangles of shape (T, 3) with T >= 1");
  TriangleMesh mesh;
  mesh.positions = checked_positions(v, where);
  auto t = f.unchecked<2>();
  for (py::ssize_t k = 0; k < f.shape(0); ++k) {
    Eigen::Vector3i tri;
    for (int r = 0; r < 3; ++r) {
      if (t(k, r) < 0 || t(k, r) >= v.shape(0))
        throw Error(where + "triangle " + std::to_string(k) + " refers to vertex " + std::to_string(t(k, r)) + " of " +
                    std::to_string(v.shape(0)));
      tri[r] = int(t(k, r));
    }
    mesh.triangles.push_back(tri);
    if (!(mesh.area(mesh.num_triangles() - 1) > 0))
      throw Error(where + "triangle " + std::to_string(k) + " has zero area");
  }
  if (!shape.face_normals) mesh.normals = vertex_normals(mesh);
  shape.mesh = std::move(mesh);
}

/// qsil.remesh: positions (V, 3) and triangles (T, 3) remeshed toward a target edge length
/// (isotropic_remesh), as a (positions, triangles) tuple.
py::tuple remesh(const Array& v, const py::array_t<long long>& f, double target_edge_length, int iterations) {
  if (v.ndim() != 2 || v.shape(1) != 3 || f.ndim() != 2 || f.shape(1) != 3)
    throw Error("remesh: expected positions (V, 3) and triangles (T, 3)");
  TriangleMesh mesh;
  auto a = v.unchecked<2>();
  for (py::ssize_t i = 0; i < v.shape(0); ++i) {
    const Vec3 p(a(i, 0), a(i, 1), a(i, 2));
    if (!p.allFinite()) throw Error("remesh: vertex " + std::to_string(i) + " is non-finite");
    mesh.positions.push_back(p);
  }
  auto t = f.unchecked<2>();
  for (py::ssize_t k = 0; k < f.shape(0); ++k) mesh.triangles.emplace_back(int(t(k, 0)), int(t(k, 1)), int(t(k, 2)));
  TriangleMesh out;
  {
    py::gil_scoped_release release;
    out = isotropic_remesh(mesh, target_edge_length, iterations);
  }
  Array pv({out.num_vertices(), 3});
  auto pa = pv.mutable_unchecked<2>();
  for (int i = 0; i < out.num_vertices(); ++i)
    for (int r = 0; r < 3; ++r) pa(i, r) = out.positions[size_t(i)][r];
  py::array_t<long long> pf({out.num_triangles(), 3});
  auto fa = pf.mutable_unchecked<2>();
  for (int k = 0; k < out.num_triangles(); ++k)
    for (int r = 0; r < 3; ++r) fa(k, r) = out.triangles[size_t(k)][r];
  return py::make_tuple(pv, pf);
}

/// Binds qsil.Scene: loading, the camera's size and sample count, shapes' vertices and triangles.
void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", "A scene loaded from Mitsuba 3 XML (geometry in world space)")
      .def(py::init([](const std::string& path, const std::map<std::string, std::string>& defines) {
             return load_scene(path, defines);
           }),
           py::arg("path"), py::arg("defines") = std::map<std::string, std::string>{},
           "Loads PATH; `defines` override <default> values (the CLI's -D name=value). Raises qsil.Error.")
      .def_property_readonly("width", [](const Scene& s) { return s.camera.width; })
      .def_property_readonly("height", [](const Scene& s) { return s.camera.height; })
      .def_property_readonly("spp", [](const Scene& s) { return s.camera.spp; }, "the scene's sample count")
      .def_property_readonly("shape_ids",
                             [](const Scene& s) {
                               std::vector<std::string> ids;
                               for (const Shape& sh : s.shapes) ids.push_back(sh.id);
                               return ids;
                             })
      .def(
          "vertices",
          [](const Scene& s, const std::string& id) {
            const TriangleMesh& mesh = s.shapes[size_t(shape_index(s, id))].mesh;
            Array out({mesh.num_vertices(), 3});
            auto a = out.mutable_unchecked<2>();
            for (int i = 0; i < mesh.num_vertices(); ++i)
              for (int r = 0; r < 3; ++r) a(i, r) = mesh.positions[size_t(i)][r];
            return out;
          },
          py::arg("shape"), "Vertex positions (V, 3) of a shape, world space (a copy)")
      .def(
          "triangles",
          [](const Scene& s, const std::string& id) {
            const TriangleMesh& mesh = s.shapes[size_t(shape_index(s, id))].mesh;
            py::array_t<int> out({mesh.num_triangles(), 3});
            auto a = out.mutable_unchecked<2>();
            for (int f = 0; f < mesh.num_triangles(); ++f)
              for (int r = 0; r < 3; ++r) a(f, r) = mesh.triangles[size_t(f)][r];
            return out;
          },
          py::arg("shape"), "Triangles (T, 3) of a shape: vertex indices, counter-clockwise = outward")
      .def("set_vertices", &set_vertices, py::arg("shape"), py::arg("positions"),
           "Sets a shape's vertex positions (V, 3) and recomputes its area-weighted vertex normals")
      .def(
          "set_resolution",
          [](Scene& s, int width, int height) {
            if (width < 1 || width > (1 << 16) || height < 1 || height > (1 << 16))
              throw Error("set_resolution(" + std::to_string(width) + ", " + std::to_string(height) +
                          "): width and height must be in [1, 65536]");
            s.camera.width = width;
            s.camera.height = height;
          },
          py::arg("width"), py::arg("height"),
          "Sets the film's size in pixels (coarse-to-fine optimisation); the field of view along the camera's fov_axis "
          "is kept, as when the XML's film size changes. Raises qsil.Error outside [1, 65536]")
      .def("set_mesh", &set_mesh, py::arg("shape"), py::arg("positions"), py::arg("triangles"),
           "Replaces a shape's mesh: positions (V, 3) and triangles (T, 3) of vertex indices, counter-clockwise = "
           "outward (after a remeshing); recomputes its vertex normals. Every later render, grad or reverse builds its "
           "edge structure (forest, creases, intersection curves) for the new mesh. Raises qsil.Error for bad input, "
           "leaving the mesh as it was");
}

/// Binds qsil.render and qsil.grad (forward mode).
void bind_forward(py::module_& m) {
  m.def(
      "render",
      [](const Scene& scene, int spp, uint64_t seed, int threads, double reg_width) {
        std::optional<RenderResult> r;
        {
          py::gil_scoped_release release;
          EstimatorConfig config = EstimatorConfig::primal();
          if (reg_width != 0) config.regularization = Regularization::for_scene(scene, reg_width);
          r = Estimator(scene, config).run(options(spp, seed, threads));
        }
        const FilmLayout layout;
        return film_image(r->film, [&](int c) { return layout.primal(c); });
      },
      py::arg("scene"), py::arg("spp") = 0, py::arg("seed") = 0, py::arg("threads") = 0, py::arg("reg_width") = 0.0,
      "The primal image (H, W, 3); spp 0: the scene's sample count; reg_width != 0: the image under "
      "boundary='regularized''s blurred visibility of that width (a fraction of the scene's bounding-box "
      "diagonal; `qsil grad --help`)");

  const auto grad =
      [](const Scene& scene, const std::vector<std::string>& params, int spp, uint64_t seed, int threads,
         const std::string& boundary, double sppi, double sppp, bool intersection_curves, double reg_width,
         int guiding_resolution, double guiding_share, double guiding_training, bool guiding_octree,
         double guiding_seeds, int was_rays, double was_kappa, double was_exponent, bool was_unbiased,
         int forest_guide_training, int forest_guide_rounds, int forest_guide_resolution, int forest_guide_depth,
         double forest_guide_share, const std::string& camera_hits, int camera_control_spp) {
        const Method method = parse_method(boundary, "boundary", kBoundaryMethods);
        const CameraHits hits = camera_hits_named(camera_hits);
        const std::vector<ParameterSpec> specs = parse_parameters(params, scene);
        std::optional<Estimator> e;
        std::optional<RenderResult> r;
        {
          py::gil_scoped_release release;
          EstimatorConfig config = EstimatorConfig::gradient(specs, method, sppi, sppp);
          config.intersection_curves = intersection_curves;
          config.camera_hits = hits;
          config.camera_control_spp = camera_control_spp;
          if (method == Method::Regularized)
            config.regularization = Regularization::for_scene(scene, reg_width);
          config.projective_guiding = {guiding_resolution, guiding_training, guiding_share, guiding_octree,
                                       guiding_seeds};
          config.warped_area = {was_rays, was_kappa, was_exponent, was_unbiased};
          config.forest_guiding = {forest_guide_training,
                                   forest_guide_rounds,
                                   {forest_guide_resolution, forest_guide_depth, forest_guide_share}};
          e.emplace(scene, std::move(config));
          r = e->run(options(spp, seed, threads));
        }
        const FilmLayout& layout = e->layout();
        Array d({py::ssize_t(specs.size()), py::ssize_t(scene.camera.height), py::ssize_t(scene.camera.width),
                 py::ssize_t(3)});
        auto a = d.mutable_unchecked<4>();
        for (int k = 0; k < int(specs.size()); ++k)
          for (int y = 0; y < scene.camera.height; ++y)
            for (int x = 0; x < scene.camera.width; ++x)
              for (int c = 0; c < 3; ++c) a(k, y, x, c) = r->film.mean(layout.derivative(k, c), x, y);
        for (int k = 0; k < int(specs.size()); ++k) {  // as the CLI warns (write_gradient_outputs)
          const ImageSum s = r->film.derivative_sum(k);
          if (!has_dominant_pixel(s, r->film)) continue;
          const std::string text = "qsil.grad: " + dominant_pixel_warning(s, k) + " (seed=)";
          if (PyErr_WarnEx(PyExc_RuntimeWarning, text.c_str(), 1) < 0) throw py::error_already_set();
        }
        return py::make_tuple(film_image(r->film, [&](int c) { return layout.primal(c); }), d);
      };
  m.def("grad", grad, py::arg("scene"), py::arg("params"), py::arg("spp") = 0, py::arg("seed") = 0,
        py::arg("threads") = 0, py::arg("boundary") = "quadric", py::arg("sppi") = 0, py::arg("sppp") = kDefaultSppp,
        py::arg("intersection_curves") = true, py::arg("reg_width") = 1e-3, py::arg("guiding_resolution") = 0,
        py::arg("guiding_share") = 0.5, py::arg("guiding_training") = 4.0, py::arg("guiding_octree") = false,
        py::arg("guiding_seeds") = 64.0, py::arg("was_rays") = 8, py::arg("was_kappa") = 1e5,
        py::arg("was_exponent") = 3.0, py::arg("was_unbiased") = false, py::arg("forest_guide_training") = 0,
        py::arg("forest_guide_rounds") = 2, py::arg("forest_guide_resolution") = 8, py::arg("forest_guide_depth") = 3,
        py::arg("forest_guide_share") = 0.5, py::arg("camera_hits") = "adaptive",
        py::arg("camera_control_spp") = kAttachedControlSpp,
        "Forward mode: (image (H, W, 3), derivatives (K, H, W, 3)) for 1-8 parameter specs "
        "('ID:translate:X,Y,Z', 'ID:rotate:X,Y,Z', 'ID:scale', 'ID:vertex:I:X,Y,Z'); a RuntimeWarning where one "
        "pixel holds half or more of a parameter's image-sum variance (a heavy tail's single sample, as `qsil grad` "
        "warns). sppi: secondary "
        "boundary-term samples per shading point on average over a pixel's samples (0: the method's default, 0.5 for "
        "quadric; for boundary='projective', boundary segments per pixel sample, default 1); sppp: primary edge "
        "samples per pixel sample (`qsil grad --help`); intersection_curves=False: do not "
        "sample the curves where surfaces cross (to measure what they add; biased where surfaces cross); reg_width: "
        "boundary='regularized''s blur width as a fraction of the scene's bounding-box diagonal (`qsil grad --help`); "
        "guiding_resolution, guiding_share, guiding_training: boundary='projective''s grid guide (0: none); "
        "guiding_octree, guiding_seeds: its octree guide from projected seeds (excludes a grid); was_rays, "
        "was_kappa, was_exponent, was_unbiased: boundary='was''s auxiliary rays; forest_guide_training (0: none), "
        "forest_guide_rounds, forest_guide_resolution, forest_guide_depth, forest_guide_share: the quadric methods' "
        "guided edge choice; camera_hits: 'adaptive', 'attached' or 'detached' camera samples on moving shapes; "
        "camera_control_spp: the pre-pass spp of their control variate (0: none; `qsil grad --help`)");
  // The keyword names before 2026-11-25 (boundary_spp, primary_samples): the same function.
  m.def("grad", grad, py::arg("scene"), py::arg("params"), py::arg("spp") = 0, py::arg("seed") = 0,
        py::arg("threads") = 0, py::arg("boundary") = "quadric", py::arg("boundary_spp") = 0,
        py::arg("primary_samples") = kDefaultSppp, py::arg("intersection_curves") = true, py::arg("reg_width") = 1e-3,
        py::arg("guiding_resolution") = 0, py::arg("guiding_share") = 0.5, py::arg("guiding_training") = 4.0,
        py::arg("guiding_octree") = false, py::arg("guiding_seeds") = 64.0, py::arg("was_rays") = 8,
        py::arg("was_kappa") = 1e5, py::arg("was_exponent") = 3.0, py::arg("was_unbiased") = false,
        py::arg("forest_guide_training") = 0, py::arg("forest_guide_rounds") = 2,
        py::arg("forest_guide_resolution") = 8, py::arg("forest_guide_depth") = 3, py::arg("forest_guide_share") = 0.5,
        py::arg("camera_hits") = "adaptive", py::arg("camera_control_spp") = kAttachedControlSpp,
        "The same, with the old keyword names boundary_spp (= sppi) and primary_samples (= sppp)");
}

/// The adjoint image (H, W, 3) of a reverse-mode run as the estimator takes it, row-major RGB.
/// Throws qsil::Error for another shape.
std::vector<double> adjoint_weights(const Scene& scene, const Array& adjoint) {
  const int W = scene.camera.width, H = scene.camera.height;
  if (adjoint.ndim() != 3 || adjoint.shape(0) != H || adjoint.shape(1) != W || adjoint.shape(2) != 3)
    throw Error("adjoint image: expected an array of shape (" + std::to_string(H) + ", " + std::to_string(W) +
                ", 3)");
  return std::vector<double>(adjoint.data(), adjoint.data() + adjoint.size());
}

/// The ReverseConfig of qsil.reverse's and qsil.ReverseEstimator's keywords (the shapes by id).
/// Throws qsil::Error for an unknown method, shape or camera-hits rule.
ReverseConfig reverse_config(const Scene& scene, const std::vector<std::string>& shapes, const std::string& boundary,
                             double sppi, double sppp, bool intersection_curves, const std::string& camera_hits,
                             int camera_control_spp) {
  ReverseConfig config{resolve_shapes(scene, shapes), parse_method(boundary, "boundary", kBoundaryMethods), sppi, sppp,
                       intersection_curves};
  config.camera_hits = camera_hits_named(camera_hits);
  config.camera_control_spp = camera_control_spp;
  return config;
}

/// A reverse-mode result as qsil.reverse returns it: 'image' (H, W, 3), 'loss', 'gradient'
/// {shape id: (V, 3)}, 'seconds', 'nonfinite', 'probed'.
py::dict reverse_dict(const ReverseResult& r, const std::vector<std::string>& shapes) {
  Array image({r.height, r.width, 3});
  std::copy(r.image.begin(), r.image.end(), image.mutable_data());
  py::dict gradient;
  for (size_t i = 0; i < shapes.size(); ++i) {
    Array g({py::ssize_t(r.gradient[i].size()), py::ssize_t(3)});
    auto a = g.mutable_unchecked<2>();
    for (size_t v = 0; v < r.gradient[i].size(); ++v)
      for (int c = 0; c < 3; ++c) a(py::ssize_t(v), c) = r.gradient[i][v][c];
    gradient[py::str(shapes[i])] = g;
  }
  py::dict out;
  out["image"] = image;
  out["loss"] = r.loss;
  out["gradient"] = gradient;
  out["seconds"] = r.seconds;
  out["nonfinite"] = r.nonfinite;
  out["probed"] = r.probed;
  return out;
}

/// qsil.ReverseEstimator: reverse mode set up once and kept across an optimiser's steps.
struct PyReverseEstimator {
  const Scene* scene;
  std::vector<std::string> shapes;
  std::unique_ptr<ReverseEstimator> estimator;
  std::mutex lock;  ///< run, render and update from several Python threads: one at a time
};

/// Binds qsil.reverse (reverse mode) and qsil.ReverseEstimator.
void bind_reverse(py::module_& m) {
  const auto reverse = [](const Scene& scene, const std::vector<std::string>& shapes, const Array& adjoint, int spp,
                          uint64_t seed, int threads, const std::string& boundary, double sppi, double sppp,
                          bool intersection_curves, const std::string& camera_hits, int camera_control_spp) {
    const ReverseConfig config =
        reverse_config(scene, shapes, boundary, sppi, sppp, intersection_curves, camera_hits, camera_control_spp);
    const std::vector<double> w = adjoint_weights(scene, adjoint);
    std::optional<ReverseResult> r;
    {
      py::gil_scoped_release release;
      const ReverseEstimator e(scene, config);
      r = e.run(w, options(spp, seed, threads));
    }
    return reverse_dict(*r, shapes);
  };
  py::class_<PyReverseEstimator>(
      m, "ReverseEstimator",
      "Reverse mode set up once for an optimisation: run() as qsil.reverse, update() after the scene's meshes "
      "changed (set_vertices: the edge forest is refitted, the ray tracer's vertices moved; set_mesh: set up anew)")
      .def(py::init([](const Scene& scene, const std::vector<std::string>& shapes, const std::string& boundary,
                       double sppi, double sppp, bool intersection_curves, bool probe_paths,
                       const std::string& camera_hits, int camera_control_spp) {
             ReverseConfig config = reverse_config(scene, shapes, boundary, sppi, sppp, intersection_curves,
                                                   camera_hits, camera_control_spp);
             config.probe_paths = probe_paths;
             auto p = std::make_unique<PyReverseEstimator>();
             p->scene = &scene;
             p->shapes = shapes;
             py::gil_scoped_release release;
             p->estimator = std::make_unique<ReverseEstimator>(scene, config);
             return p;
           }),
           py::arg("scene"), py::arg("shapes"), py::arg("boundary") = "quadric", py::arg("sppi") = 0,
           py::arg("sppp") = kDefaultSppp, py::arg("intersection_curves") = true, py::arg("probe_paths") = true,
           py::arg("camera_hits") = "adaptive", py::arg("camera_control_spp") = kAttachedControlSpp,
           py::keep_alive<1, 2>(),
           "Sets up reverse mode for `shapes` of `scene` (kept alive by the estimator); arguments as for "
           "qsil.reverse (update() keeps the control variate's per-pixel c of the set-up: unbiased for any c); "
           "probe_paths=False traces every path with dual numbers (the same estimates, slower: "
           "for timing, ReverseConfig::probe_paths)")
      .def(
          "run",
          [](PyReverseEstimator& self, const Array& adjoint, int spp, uint64_t seed, int threads) {
            const std::vector<double> w = adjoint_weights(*self.scene, adjoint);
            std::optional<ReverseResult> r;
            {
              py::gil_scoped_release release;
              const std::lock_guard<std::mutex> hold(self.lock);
              r = self.estimator->run(w, options(spp, seed, threads));
            }
            return reverse_dict(*r, self.shapes);
          },
          py::arg("adjoint"), py::arg("spp") = 0, py::arg("seed") = 0, py::arg("threads") = 0,
          "As qsil.reverse on the scene as of the last update(): a dict with 'image', 'loss', 'gradient', "
          "'seconds', 'nonfinite', 'probed'")
      .def(
          "render",
          [](PyReverseEstimator& self, int spp, uint64_t seed, int threads) {
            std::optional<RenderResult> r;
            {
              py::gil_scoped_release release;
              const std::lock_guard<std::mutex> hold(self.lock);
              r = self.estimator->render(options(spp, seed, threads));
            }
            const FilmLayout layout;
            return film_image(r->film, [&](int c) { return layout.primal(c); });
          },
          py::arg("spp") = 0, py::arg("seed") = 0, py::arg("threads") = 0,
          "The primal image (H, W, 3) of the scene as of the last update(), equal to qsil.render's for the same "
          "spp and seed, without its set-up (an optimiser's primal render each step)")
      .def(
          "update",
          [](PyReverseEstimator& self) {
            std::optional<ReverseUpdate> u;
            {
              py::gil_scoped_release release;
              const std::lock_guard<std::mutex> hold(self.lock);
              u = self.estimator->update();
            }
            py::dict out;
            out["refitted"] = u->refitted;
            out["reason"] = u->reason;
            out["box_growth"] = u->box_growth;
            out["seconds"] = u->seconds;
            out["edge_seconds"] = u->edge_seconds;
            return out;
          },
          "After the scene's meshes changed: a dict with 'refitted' (the edge forest was refitted, not built anew), "
          "'reason' (why it was built anew), 'box_growth', 'seconds' (the whole update), 'edge_seconds' (the edge "
          "structure's part)");
  m.def("reverse", reverse, py::arg("scene"), py::arg("shapes"), py::arg("adjoint"), py::arg("spp") = 0,
        py::arg("seed") = 0, py::arg("threads") = 0, py::arg("boundary") = "quadric", py::arg("sppi") = 0,
        py::arg("sppp") = kDefaultSppp, py::arg("intersection_curves") = true, py::arg("camera_hits") = "adaptive",
        py::arg("camera_control_spp") = kAttachedControlSpp,
        "Reverse mode: for the loss L = sum(adjoint * I), a dict with 'image' (H, W, 3), 'loss' (of that image), "
        "'gradient' {shape id: dL/dx (V, 3)}, 'seconds', 'nonfinite', 'probed'; sppi, sppp, intersection_curves, "
        "camera_hits and camera_control_spp as for grad (the chosen shapes are the moving ones)");
  // The keyword names before 2026-11-25 (boundary_spp, primary_samples): the same function.
  m.def("reverse", reverse, py::arg("scene"), py::arg("shapes"), py::arg("adjoint"), py::arg("spp") = 0,
        py::arg("seed") = 0, py::arg("threads") = 0, py::arg("boundary") = "quadric", py::arg("boundary_spp") = 0,
        py::arg("primary_samples") = kDefaultSppp, py::arg("intersection_curves") = true,
        py::arg("camera_hits") = "adaptive", py::arg("camera_control_spp") = kAttachedControlSpp,
        "The same, with the old keyword names boundary_spp (= sppi) and primary_samples (= sppp)");
}

}  // namespace
}  // namespace qsil

PYBIND11_MODULE(qsil, m) {
  using namespace qsil;
  m.doc() = "qsil: a differentiable path tracer with quadric-based silhouette sampling (Python bindings)";
  py::register_exception<Error>(m, "Error", PyExc_ValueError);
  qsil::bind_scene(m);
  qsil::bind_forward(m);
  qsil::bind_reverse(m);
  m.def("remesh", &qsil::remesh, py::arg("positions"), py::arg("triangles"), py::arg("target_edge_length"),
        py::arg("iterations") = 3,
        "Isotropic remeshing (CGAL's Polygon Mesh Processing) of a manifold, consistently oriented triangle mesh "
        "toward edges of target_edge_length: (positions (V', 3), triangles (T', 3)), orientation and border kept. "
        "Raises qsil.Error for a bad target, iterations < 1 or a mesh CGAL cannot hold");
}
