// The active set A: the independent equality rows (factored once, in the Workspace) plus the
// inequality rows the clamping loop pins; its orthonormal basis, null space and Δq0.
#include <algorithm>
#include <cmath>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

// |b - A q| below this is round-off, not drift: Δq0 is skipped.
constexpr double kDriftTolerance = 1e-14;

// u -= B t over the rows the basis columns with t_k != 0 are non-zero on (the others add 0).
template <typename T>
void subtractBasisProduct(const Workspace& w, const T& t, Eigen::VectorXd& u) {
  const int r = static_cast<int>(t.size());
  int lo = w.n, hi = 0;
  for (int k = 0; k < r; ++k)
    if (t(k) != 0.0) {
      lo = std::min(lo, w.basis_span[k].begin);
      hi = std::max(hi, w.basis_span[k].end);
    }
  if (lo < hi) u.segment(lo, hi - lo).noalias() -= w.basis.block(lo, 0, hi - lo, r) * t;
}

}  // namespace

Workspace::Range nonZeroSpan(const Eigen::Ref<const Eigen::VectorXd>& x) {
  int lo = 0, hi = static_cast<int>(x.size());
  while (lo < hi && x(lo) == 0.0) ++lo;
  while (hi > lo && x(hi - 1) == 0.0) --hi;
  return lo < hi ? Workspace::Range{lo, hi} : Workspace::Range{0, 0};
}

// Back to the equality rows only. The equality part of basis / factor is written once (in the
// constructor) and pinned rows only append after it; the null-space basis and the reference
// projector are restored only when pinned rows changed them.
void resetActiveSet(Workspace& w, Path path) {
  const int r = w.eq_rank;
  w.rank = r;
  if (r > 0) {
    for (int i = 0; i < r; ++i) {  // b - A q over the rows' few non-zero terms
      double v = w.eq_rhs(i);
      for (int t = w.eq_begin[i]; t < w.eq_begin[i + 1]; ++t) v -= w.eq_coef[t] * w.q(w.eq_dof[t]);
      w.active_rhs(i) = v;
    }
  }
  w.mask_mode = r == 0;
  w.mask.setOnes();
  w.null_dim = w.n - r;
  if (!w.mask_mode && w.nullspace_dirty) {
    w.nullspace.leftCols(w.null_dim) = w.eq_nullspace.leftCols(w.null_dim);
    std::copy(w.eq_null_span.begin(), w.eq_null_span.begin() + w.null_dim, w.null_span.begin());
    w.nullspace_dirty = false;
    w.null_groups = w.eq_null_groups;  // reserved: no allocation
    w.null_groups_cols = w.null_dim;
    w.null_ranges_dirty = w.eq_null_groups.empty();
  }
  if (path == Path::Reference && w.projector0_dirty) {
    w.projector0 = w.eq_projector0;
    w.projector0_dirty = false;
  }
  std::fill(w.ineq_active.begin(), w.ineq_active.end(), 0);
  std::fill(w.ineq_reported.begin(), w.ineq_reported.end(), 0);
  w.carried_structure = false;  // the factorisation no longer holds the carried rows
}

// Δq0 = A⁺ (b_A - A q) = basis * factor⁻¹ * active_rhs (minimum-norm solution). Rows that hold
// to round-off (|b - A q| ≤ 1e-14, the usual case for equalities between iterations) need no
// correction, so Δq0 is zero without the two products.
void computeDq0(Workspace& w) {
  const int r = w.rank;
  w.dq0.setZero();
  if (r == 0 || !(w.active_rhs.head(r).cwiseAbs().maxCoeff() > kDriftTolerance)) return;
  auto y = w.y.head(r);
  y = w.active_rhs.head(r);
  w.factor.topLeftCorner(r, r).triangularView<Eigen::Lower>().solveInPlace(y);
  w.dq0.noalias() = w.basis.leftCols(r) * y;
}

// Adds row c (in w.tmp_n) pinned so that c^T (q + Δq) = c^T q + rhs_delta. Returns false when
// the row depends linearly on the active set (then nothing changes). The products that meet c or
// u run over the rows where those are non-zero only (a limit or a band touches one or two dofs,
// and u then lies on the constrained dofs it was projected against), and the Householder
// reflection of N touches only the columns its vector is non-zero in: a spine band's few, not
// all of N (the runtime re-pins the carried rows after every release).
bool addActiveRow(Workspace& w, double rhs_delta, int single_dof, Path path, double tolerance) {
  const int r = w.rank;
  const Eigen::VectorXd& c = w.tmp_n;
  auto t = w.y.head(r);
  Eigen::VectorXd& u = w.tmp_n2;
  u = c;
  if (r > 0) {
    const Workspace::Range cs = nonZeroSpan(c);
    t.noalias() = w.basis.block(cs.begin, 0, cs.end - cs.begin, r).transpose() * c.segment(cs.begin, cs.end - cs.begin);
    subtractBasisProduct(w, t, u);
  }
  const double cn = c.norm();
  if (!(u.norm() > tolerance * cn)) return false;
  if (r > 0) {  // second Gram-Schmidt sweep keeps the basis orthonormal to round-off
    const Workspace::Range us = nonZeroSpan(u);
    auto t2 = w.dq0.head(r);  // dq0 is recomputed after rows are added
    t2.noalias() = w.basis.block(us.begin, 0, us.end - us.begin, r).transpose() * u.segment(us.begin, us.end - us.begin);
    subtractBasisProduct(w, t2, u);
    t += t2;
    w.factor.row(r).head(r) = t.transpose();
  }
  const double un = u.norm();
  u /= un;
  w.basis.col(r) = u;
  w.basis_span[r] = nonZeroSpan(u);
  w.factor(r, r) = un;
  w.active_rhs(r) = rhs_delta;
  w.rank = r + 1;

  if (w.mask_mode && single_dof >= 0) {
    w.mask(single_dof) = 0.0;
  } else {
    w.nullspace_dirty = true;
    w.null_ranges_dirty = true;
    if (w.mask_mode) {  // materialise the diagonal projector's basis: the unmasked unit vectors
      w.nullspace.setZero();
      int k = 0;
      for (int i = 0; i < w.n; ++i)
        if (w.mask(i) != 0.0) {
          w.null_span[k] = Workspace::Range{i, i + 1};
          w.nullspace(i, k++) = 1.0;
        }
      w.mask_mode = false;
    }
    // Householder reflection H with H (Nᵀ u) = α e_last; then N H's last column is ±u: drop it.
    // N H = N - (2 / vᵀv) (N v) vᵀ changes only the columns where v is non-zero.
    const int d = w.null_dim;
    const Workspace::Range us = nonZeroSpan(u);
    auto v = w.tmp_n.head(d);  // c is no longer needed
    v.noalias() = w.nullspace.block(us.begin, 0, us.end - us.begin, d).transpose() * u.segment(us.begin, us.end - us.begin);
    const double yn = v.norm();
    const double alpha = v(d - 1) > 0 ? -yn : yn;
    v(d - 1) -= alpha;
    const double vv = v.squaredNorm();
    if (vv > 0) {
      Eigen::VectorXd& nv = w.tmp_n2;  // u is no longer needed (copied into basis)
      nv.setZero();
      for (int k = 0; k < d; ++k)
        if (v(k) != 0.0) nv.noalias() += v(k) * w.nullspace.col(k);
      nv *= 2.0 / vv;  // (2 / vᵀv) N v, then each changed column less v_k times it
      for (int k = 0; k < d; ++k)
        if (v(k) != 0.0) {
          w.nullspace.col(k).noalias() -= v(k) * nv;
          w.null_span[k] = nonZeroSpan(w.nullspace.col(k));
        }
    }
  }
  w.null_dim -= 1;
  if (path == Path::Reference) {
    w.projector0.noalias() -= w.basis.col(r) * w.basis.col(r).transpose();
    w.projector0_dirty = true;
  }
  return true;
}

}  // namespace embody::ik::detail
