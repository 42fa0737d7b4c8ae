/// @file offset_lp.cpp
/// [QSS Eq. 6] solved with COIN-OR CLP. The only file of qsil that includes CLP.

#include "offset_lp.h"

#include "extremes.h"

#include <coin/ClpSimplex.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace qsil::edgetree {

namespace {
/// solve_direct's result, with, when the LP is unbounded and CLP gives it, its ray: a unit
/// direction (rho, D) along which every constraint stays satisfied and rho grows (`has_ray`,
/// checked against the rows).
struct DirectResult : OffsetLpResult {
  bool has_ray = false;
  double ray_rho = 0.0;
  Vec3 ray_d = Vec3::Zero();
};

DirectResult solve_direct(std::span<const Vec4> planes) {
  DirectResult out;
  out.solves = 1;
  const int m = int(planes.size());
  if (m == 0) {
    out.status = OffsetLpResult::Status::Unbounded;
    return out;
  }
  // Columns: 0 = rho, 1..3 = Dx, Dy, Dz. Row i: n_i . D - rho >= -w_i.
  const int ncol = 4;
  std::vector<CoinBigIndex> start(ncol + 1);
  std::vector<int> index;
  std::vector<double> value;
  index.reserve(size_t(4) * m);
  value.reserve(size_t(4) * m);
  for (int c = 0; c < ncol; ++c) {
    start[c] = CoinBigIndex(index.size());
    for (int i = 0; i < m; ++i) {
      const double v = c == 0 ? -1.0 : planes[i][c - 1];
      if (v == 0.0) continue;
      index.push_back(i);
      value.push_back(v);
    }
  }
  start[ncol] = CoinBigIndex(index.size());
  std::vector<double> collb(ncol, -COIN_DBL_MAX), colub(ncol, COIN_DBL_MAX);
  std::vector<double> obj = {-1.0, 0.0, 0.0, 0.0};  // minimise -rho
  std::vector<double> rowlb(m), rowub(m, COIN_DBL_MAX);
  for (int i = 0; i < m; ++i) rowlb[i] = -planes[i][3];

  ClpSimplex model;
  model.setLogLevel(0);
  model.loadProblem(ncol, m, start.data(), index.data(), value.data(), collb.data(), colub.data(), obj.data(),
                    rowlb.data(), rowub.data());
  model.primal();
  if (model.isProvenOptimal()) {
    const double* x = model.primalColumnSolution();
    out.status = OffsetLpResult::Status::Optimal;
    out.rho = x[0];
    out.point = Vec3(x[1], x[2], x[3]);
    // Recompute rho from the planes: the solver's tolerances must not make us optimistic.
    double rho = kInf;
    for (const Vec4& q : planes) rho = std::min(rho, q.head<3>().dot(out.point) + q[3]);
    out.rho = rho;
  } else if (model.isProvenDualInfeasible()) {
    out.status = OffsetLpResult::Status::Unbounded;
    if (double* ray = model.unboundedRay()) {
      // Kept only if it is one (normalised): rho grows along it and every row holds, up to a
      // relative 1e-9; otherwise the caller falls back to adding planes by stride.
      const Vec4 r(ray[0], ray[1], ray[2], ray[3]);
      delete[] ray;
      const double len = r.norm();
      if (len > 0.0 && std::isfinite(len)) {
        const Vec4 u = r / len;
        bool holds = u[0] > 1e-9;
        for (size_t i = 0; holds && i < planes.size(); ++i)
          holds = planes[i].head<3>().dot(u.tail<3>()) - u[0] >= -1e-9;
        if (holds) {
          out.has_ray = true;
          out.ray_rho = u[0];
          out.ray_d = u.tail<3>();
        }
      }
    }
  } else if (model.isProvenPrimalInfeasible()) {
    out.status = OffsetLpResult::Status::Infeasible;
  } else {
    out.status = OffsetLpResult::Status::Failed;
  }
  return out;
}
}  // namespace

OffsetLpResult solve_offset_lp(std::span<const Vec4> planes) {
  // Constraint generation: solve on a subset of planes, add the most violated planes, repeat.
  // A subset's optimum rho_sub bounds the full optimum from above (fewer constraints), so
  // rho_sub <= 0 already proves rho <= 0; a subset optimum that violates no plane is the full
  // optimum. The subset starts with the planes of extremal normals along 13 directions (26
  // planes at most). A subset that is unbounded has its normals in an open half-space; CLP's
  // ray names the planes that break it, and those are added (without them a closed set whose
  // closing planes are extreme along none of the 13 directions, as a bumpy mesh's large nodes
  // have, ran all 50 rounds and then the whole LP: 0.75 s for one node of 19 762 planes).
  const int m = int(planes.size());
  if (m <= 64) return solve_direct(planes);
  std::vector<char> in(m, 0);
  std::vector<Vec4> sub;
  auto add = [&](int i) {
    if (!in[i]) {
      in[i] = 1;
      sub.push_back(planes[i]);
    }
  };
  static const Vec3 dirs[13] = {Vec3(1, 0, 0),  Vec3(0, 1, 0),  Vec3(0, 0, 1), Vec3(1, 1, 1),  Vec3(1, 1, -1),
                                Vec3(1, -1, 1), Vec3(-1, 1, 1), Vec3(1, 1, 0), Vec3(1, -1, 0), Vec3(1, 0, 1),
                                Vec3(1, 0, -1), Vec3(0, 1, 1),  Vec3(0, 1, -1)};
  for (const Vec3& d : dirs) {
    const auto [imin, imax] = extreme_indices(m, [&](int i) { return d.dot(planes[i].head<3>()); });
    add(imin);
    add(imax);
  }
  int solves = 0;
  for (int iter = 0; iter < 50; ++iter) {
    DirectResult r = solve_direct(sub);
    r.solves = ++solves;
    if (r.status != OffsetLpResult::Status::Optimal) {
      if (int(sub.size()) == m) return r;
      if (r.status == OffsetLpResult::Status::Unbounded && r.has_ray) {
        // The subset's normals lie in an open half-space; the planes whose normals leave the
        // ray's (n.D_ray - rho_ray < 0, the constraints the ray breaks) are what the subset
        // lacks. None: the ray is one of the full problem too, which is unbounded.
        std::vector<std::pair<double, int>> viol;
        for (int i = 0; i < m; ++i) {
          if (in[i]) continue;
          const double v = planes[i].head<3>().dot(r.ray_d) - r.ray_rho;
          if (v < 0.0) viol.push_back({v, i});
        }
        if (viol.empty()) return std::move(static_cast<OffsetLpResult&>(r));
        const size_t k = std::min<size_t>(viol.size(), 32);
        std::partial_sort(viol.begin(), viol.begin() + k, viol.end());
        for (size_t j = 0; j < k; ++j) add(viol[j].second);
        continue;
      }
      // Unbounded without a ray (or failed) on the subset: add a stride of planes and retry.
      const int step = std::max(1, m / 64);
      for (int i = iter % step; i < m; i += step) add(i);
      continue;
    }
    if (r.rho <= 0.0) return r;  // rho_full <= rho_sub <= 0
    // Most violated planes at the subset's optimum.
    std::vector<std::pair<double, int>> viol;
    for (int i = 0; i < m; ++i) {
      if (in[i]) continue;
      const double v = planes[i].head<3>().dot(r.point) + planes[i][3];
      if (v < r.rho * (1.0 - 1e-12)) viol.push_back({v, i});
    }
    if (viol.empty()) {
      double rho = kInf;
      for (const Vec4& q : planes) rho = std::min(rho, q.head<3>().dot(r.point) + q[3]);
      r.rho = rho;
      return r;
    }
    const size_t k = std::min<size_t>(viol.size(), 32);
    std::partial_sort(viol.begin(), viol.begin() + k, viol.end());
    for (size_t j = 0; j < k; ++j) add(viol[j].second);
  }
  OffsetLpResult full = solve_direct(planes);
  full.solves = solves + 1;
  return full;
}

}  // namespace qsil::edgetree
