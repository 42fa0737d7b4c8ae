/// @file offset_lp.cpp
/// [QSS Eq. 6] solved with COIN-OR CLP. The only file of qsil that includes CLP.

#include "edgetree/offset_lp.h"

#include <coin/ClpSimplex.hpp>

#include <vector>

namespace qsil::edgetree {

OffsetLpResult solve_offset_lp(std::span<const Vec4> planes) {
  OffsetLpResult out;
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
  model.loadProblem(ncol, m, start.data(), index.data(), value.data(), collb.data(),
                    colub.data(), obj.data(), rowlb.data(), rowub.data());
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
  } else if (model.isProvenPrimalInfeasible()) {
    out.status = OffsetLpResult::Status::Infeasible;
  } else {
    out.status = OffsetLpResult::Status::Failed;
  }
  return out;
}

}  // namespace qsil::edgetree
