// The fast priority pass: reduced coordinates over the null space of the active rows, the
// projected Jacobian never formed, sparsity of J̃ and W exploited (docs/ik.md).
#include <algorithm>
#include <cmath>
#include <limits>

#include "ik/small_cholesky.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

// Products below this many multiply-adds skip Eigen's blocked GEMM (addProduct).
constexpr Eigen::Index kLazyProductLimit = 400;

// dst += sign * a * b. Small products (a few hundred multiply-adds, the usual size here) skip
// Eigen's blocked GEMM, whose packing costs more than the arithmetic at these sizes.
template <typename Dst, typename A, typename B>
void addProduct(Dst&& dst, const A& a, const B& b, double sign) {
  if (a.rows() * a.cols() * b.cols() <= kLazyProductLimit) {
    if (sign > 0)
      dst.noalias() += a.lazyProduct(b);
    else
      dst.noalias() -= a.lazyProduct(b);
  } else {
    if (sign > 0)
      dst.noalias() += a * b;
    else
      dst.noalias() -= a * b;
  }
}

// J̃ = J N over N's sparsity: consecutive columns with the same span of non-zero rows form a
// group (a free dof's unit column, or the constrained dofs' block), and each group costs a
// product over its rows only. The groups are found again only after N changed.
void nullspaceProduct(Workspace& w, int r) {
  if (w.null_ranges_dirty || w.null_groups_cols != r) {
    w.null_groups.clear();
    for (int c = 0; c < r; ++c) {
      int lo = 0, hi = w.n;
      while (lo < hi && w.nullspace(lo, c) == 0.0) ++lo;
      while (hi > lo && w.nullspace(hi - 1, c) == 0.0) --hi;
      if (!w.null_groups.empty() && w.null_groups.back().row_begin == lo && w.null_groups.back().row_end == hi &&
          w.null_groups.back().col_end == c)
        w.null_groups.back().col_end = c + 1;
      else
        w.null_groups.push_back({c, c + 1, lo, hi});
    }
    w.null_ranges_dirty = false;
    w.null_groups_cols = r;
    if (!w.nullspace_dirty && r == w.n - w.eq_rank && w.eq_null_groups.empty()) w.eq_null_groups = w.null_groups;
  }
  for (const Workspace::ColumnGroup& g : w.null_groups) {
    const int rows = g.row_end - g.row_begin, cols = g.col_end - g.col_begin;
    auto dst = w.reduced_jacobian.middleCols(g.col_begin, cols);
    if (rows == 0)
      dst.setZero();
    else if (rows == 1 && cols == 1)  // a free dof's unit column (±1 after a reflection)
      dst.col(0) = w.nullspace(g.row_begin, g.col_begin) * w.jacobian.col(g.row_begin);
    else if (rows == 1)
      dst.noalias() = w.jacobian.col(g.row_begin) * w.nullspace.block(g.row_begin, g.col_begin, 1, cols);
    else
      dst.noalias() = w.jacobian.middleCols(g.row_begin, rows) * w.nullspace.block(g.row_begin, g.col_begin, rows, cols);
  }
}

// Dense mode: the reduced columns (and their ranges) whose column group of N reaches any of the
// dof ranges `dofs` (a level's recruited dofs), into w.dense_support / w.dense_support_ranges.
void denseSupport(Workspace& w, const std::vector<Workspace::Range>& dofs, int r) {
  w.dense_support.clear();
  w.dense_support_ranges.clear();
  for (const Workspace::ColumnGroup& g : w.null_groups) {
    bool reaches = false;
    for (const Workspace::Range& d : dofs)
      if (d.begin < g.row_end && g.row_begin < d.end) {
        reaches = true;
        break;
      }
    if (!reaches || g.col_begin >= r) continue;
    const int end = std::min(g.col_end, r);
    for (int c = g.col_begin; c < end; ++c) w.dense_support.push_back(c);
    if (!w.dense_support_ranges.empty() && w.dense_support_ranges.back().end == g.col_begin)
      w.dense_support_ranges.back().end = end;
    else
      w.dense_support_ranges.push_back({g.col_begin, end});
  }
}

// Calls f(lo, hi) for every non-empty intersection of two sorted lists of disjoint [lo, hi).
template <typename F>
void forEachOverlap(const std::vector<Workspace::Range>& a, const std::vector<Workspace::Range>& b, F&& f) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const int lo = std::max(a[i].begin, b[j].begin), hi = std::min(a[i].end, b[j].end);
    if (lo < hi) f(lo, hi);
    if (a[i].end < b[j].end)
      ++i;
    else
      ++j;
  }
}

// The rows marked in `mark` (first r entries) as sorted ranges.
void markedRanges(const std::vector<char>& mark, int r, std::vector<Workspace::Range>& out) {
  out.clear();
  for (int i = 0; i < r;) {
    if (!mark[i]) {
      ++i;
      continue;
    }
    const int lo = i;
    while (i < r && mark[i]) ++i;
    out.push_back({lo, i});
  }
}

}  // namespace

// The fast pass works in reduced coordinates z (Δq = Δq0 + N Δz, or a diagonal mask when only
// single-dof rows are active) and never forms a projected Jacobian Ĵ = J̃ (I - W Wᵀ): with W the
// orthonormal rows the higher levels took (r x s),
//   G       = Ĵ Ĵᵀ = J̃ J̃ᵀ - (J̃W)(J̃W)ᵀ
//   Ĵᵀ y    = J̃ᵀ y - W (J̃W)ᵀ y
//   Ĵᵀ L⁻ᵀ  = (J̃ᵀ - W (J̃W)ᵀ) L⁻ᵀ         (the level's new orthonormal rows, G = L Lᵀ)
// and it exploits sparsity. In mask mode a level's J̃ is non-zero only on the dofs its tasks
// recruit (a foot: 20 of the humanoid's 61), kept as sorted ranges of dof indices; W is kept as
// one block of columns per level, each non-zero only on the ranges of rows of its level and of
// the blocks it was projected against. Products with W then run over the overlapping ranges
// only (a hand shares just the root with the feet), and the last active level skips the
// projector update altogether. Dense mode (equality rows, N = [free dofs' unit columns | the
// constrained dofs' block]) does the same over the reduced columns whose group of N reaches a
// level's dofs (denseSupport).
void fastPass(const Model& model, Workspace& w, const SolveOptions& o) {
  const bool maskMode = w.mask_mode;
  const int r = maskMode ? w.n : w.null_dim;
  // The levels' steps accumulate in reduced coordinates z; Δq = Δq0 + N z (or Δq0 + z) once at
  // the end. The compensated errors use J Δq = J Δq0 + J̃ z.
  auto z = w.small_z.head(r);
  z.setZero();
  auto jdq0 = w.small_rows.head(w.rows);
  if (w.rank > 0)
    jdq0.noalias() = w.jacobian * w.dq0;
  else
    jdq0.setZero();
  // Mask mode reads J̃ = J diag(mask) straight from J. Products with W may even use J itself:
  // W's rows at pinned dofs are zero, as W lies in the null space of the active rows.
  if (!maskMode) nullspaceProduct(w, r);
  const Eigen::MatrixXd& jFull = maskMode ? w.jacobian : w.reduced_jacobian;
  int lastActive = -1;
  for (size_t k = 0; k < model.levels.size(); ++k)
    if (levelActive(model.levels[k], w)) lastActive = static_cast<int>(k);
  int s = 0;       // columns of W
  int blocks = 0;  // W's blocks: block b has columns block_begin[b] + [0, block_size[b])
  for (size_t k = 0; k < model.levels.size(); ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w) || s >= r) continue;
    const int m = level.rows;
    // The level's support in reduced coordinates: its recruited dofs in mask mode; in dense mode
    // the columns of N that reach any of them (N's column groups over the level's dof ranges).
    if (!maskMode) denseSupport(w, w.level_ranges[k], r);
    const std::vector<int>& support = maskMode ? w.level_support[k] : w.dense_support;
    const std::vector<Workspace::Range>& ranges = maskMode ? w.level_ranges[k] : w.dense_support_ranges;
    const int p = static_cast<int>(support.size());
    const bool gather = maskMode || p < r;
    const auto jRows = jFull.middleRows(level.first_row, m);

    // J̃ on the level's support: gathered (mask mode: J diag(mask) read straight from J), or the
    // block of J N when the level reaches every reduced coordinate.
    if (gather) {
      auto g = w.gathered_j.topLeftCorner(m, p);
      for (int i = 0; i < p; ++i) {
        const int c = support[i];
        if (!maskMode)
          g.col(i) = w.reduced_jacobian.col(c).segment(level.first_row, m);
        else if (w.rank == 0 || w.mask(c) != 0.0)  // no pinned dof: J̃ = J
          g.col(i) = w.jacobian.col(c).segment(level.first_row, m);
        else
          g.col(i).setZero();
      }
    }
    const Eigen::Ref<const Eigen::MatrixXd> js =
        gather ? Eigen::Ref<const Eigen::MatrixXd>(w.gathered_j.topLeftCorner(m, p))
               : Eigen::Ref<const Eigen::MatrixXd>(w.reduced_jacobian.block(level.first_row, 0, m, r));
    // J̃W block by block, over the rows the level shares with each block.
    auto jw = w.level_jw[k].leftCols(s);
    for (int b = 0; b < blocks; ++b) {
      auto jwb = jw.middleCols(w.block_begin[b], w.block_size[b]);
      jwb.setZero();
      bool touched = false;
      forEachOverlap(ranges, w.block_ranges[b], [&](int lo, int hi) {
        addProduct(jwb, jRows.middleCols(lo, hi - lo), w.row_space.block(lo, w.block_begin[b], hi - lo, w.block_size[b]), 1.0);
        touched = true;
      });
      w.block_touched[b] = touched ? 1 : 0;
    }

    Eigen::VectorXd& res = w.level_res[k];
    res = w.error.segment(level.first_row, m);
    res -= jdq0.segment(level.first_row, m);  // compensated error
    if (gather) {
      auto zs = w.small_b.head(p);
      for (int i = 0; i < p; ++i) zs(i) = z(support[i]);
      res.noalias() -= js * zs;
    } else {
      res.noalias() -= js * z;
    }

    Eigen::MatrixXd& gram = w.level_gram[k];  // lower triangle only: the kernels read just that
    gram.setZero();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(js);
    if (s > 0) gram.selfadjointView<Eigen::Lower>().rankUpdate(jw, -1.0);
    const LevelDamping d = levelDamping(gram, w, k, o);

    // Damped step: Δz = Ĵᵀ (G + λ² I)⁻¹ res.
    Eigen::VectorXd& y = w.level_y[k];
    y = res;
    if (d.lambda2 > 0) {
      Eigen::MatrixXd& damped = w.level_factor2[k];
      damped = gram;
      damped.diagonal().array() += d.lambda2;
      // G + λ² I with λ² > 0 is positive definite unless round-off made G indefinite by more
      // than λ²; then this level takes no step rather than a wrong one.
      if (detail::choleskyInPlace(damped, w.level_factor2_inv[k]))
        detail::choleskySolve(damped, w.level_factor2_inv[k], y.data());
      else
        y.setZero();
    } else if (d.gram_pd && d.sigma_min > o.rank_tolerance) {
      detail::choleskySolve(w.level_factor[k], w.level_factor_inv[k], y.data());
    } else {  // λ = 0 on a rank-deficient level: only with damping_max = 0
      truncatedSolve(gram, w, k, o, y);
    }
    auto dz = w.tmp_n.head(r);
    if (gather) {
      auto jty = w.small_a.head(p);
      jty.noalias() = js.transpose() * y;
      dz.setZero();
      for (int i = 0; i < p; ++i) dz(support[i]) = jty(i);
    } else {
      dz.noalias() = js.transpose() * y;
    }
    for (int b = 0; b < blocks; ++b) {
      if (!w.block_touched[b]) continue;
      const int c0 = w.block_begin[b], nb = w.block_size[b];
      auto wy = w.small_b.head(nb);
      wy.noalias() = jw.middleCols(c0, nb).transpose() * y;
      for (const Workspace::Range& g : w.block_ranges[b])
        dz.segment(g.begin, g.end - g.begin).noalias() -= w.row_space.block(g.begin, c0, g.end - g.begin, nb) * wy;
    }
    if (const double cap = levelStepScale(dz.norm(), o); cap < 1.0) dz *= cap;
    z += dz;

    if (static_cast<int>(k) == lastActive) break;  // nothing below needs this level's rows

    // Projector update (undamped, rank-thresholded): append an orthonormal basis of Ĵ's rows to
    // W as a new block. Ĵᵀ = J̃ᵀ - W (J̃W)ᵀ first (in `jt`, r x m, non-zero on the marked rows).
    auto jt = w.level_cols.topLeftCorner(r, m);
    std::fill(w.row_mark.begin(), w.row_mark.begin() + r, 0);
    if (gather) {
      for (const Workspace::Range& g : ranges) {
        jt.middleRows(g.begin, g.end - g.begin).setZero();
        std::fill(w.row_mark.begin() + g.begin, w.row_mark.begin() + g.end, 1);
      }
      for (int i = 0; i < p; ++i) jt.row(support[i]) = js.col(i).transpose();
    } else {
      jt = js.transpose();
      std::fill(w.row_mark.begin(), w.row_mark.begin() + r, 1);
    }
    for (int b = 0; b < blocks; ++b) {
      if (!w.block_touched[b]) continue;
      const int c0 = w.block_begin[b], nb = w.block_size[b];
      for (const Workspace::Range& g : w.block_ranges[b]) {
        const int len = g.end - g.begin;
        for (int i = g.begin; i < g.end; ++i)
          if (!w.row_mark[i]) {
            jt.row(i).setZero();
            w.row_mark[i] = 1;
          }
        addProduct(jt.middleRows(g.begin, len), w.row_space.block(g.begin, c0, len, nb), jw.middleCols(c0, nb).transpose(), -1.0);
      }
    }
    std::vector<Workspace::Range>& newRanges = w.block_ranges[blocks];
    markedRanges(w.row_mark, r, newRanges);

    int added = 0;
    double smallest = 0.0;
    if (d.gram_pd && d.sigma_min > o.rank_tolerance && m <= r - s) {
      // Full rank: U = Ĵᵀ L⁻ᵀ (no eigen-decomposition), row range by row range.
      added = m;
      smallest = d.sigma_min;
      auto u = w.row_space.block(0, s, r, m);
      for (int i = 0, next = 0; i < static_cast<int>(newRanges.size()); ++i) {
        const Workspace::Range& g = newRanges[i];
        u.middleRows(next, g.begin - next).setZero();
        auto rows = u.middleRows(g.begin, g.end - g.begin);
        rows = jt.middleRows(g.begin, g.end - g.begin);
        detail::solveRightLowerTransposed(w.level_factor[k], w.level_factor_inv[k], rows);
        next = g.end;
        if (i + 1 == static_cast<int>(newRanges.size())) u.bottomRows(r - g.end).setZero();
      }
    } else {
      // Rank-deficient level: a pivoted Cholesky of G picks rows I of Ĵ that span its row space
      // (pivots > tolerance²); then U = Ĵ_Iᵀ L_II⁻ᵀ as for a full-rank level. An eigen-
      // decomposition would do too, at ten times the cost for a 24-row level (the seated legs).
      Eigen::MatrixXd& work = w.level_factor2[k];
      Eigen::VectorXi& perm = w.level_perm[k];
      added = detail::pivotedCholesky(gram, o.rank_tolerance * o.rank_tolerance, r - s, work, perm,
                                      w.level_factor2_inv[k]);
      if (added == 0) continue;
      auto lower = work.topLeftCorner(added, added);
      auto linvT = w.level_inverse[k].topLeftCorner(added, added);  // L_II⁻ᵀ
      linvT.setIdentity();
      detail::solveRightLowerTransposed(lower, w.level_factor2_inv[k], linvT);
      auto coef = w.level_solve.topLeftCorner(m, added);
      coef.setZero();
      for (int a = 0; a < added; ++a) coef.row(perm(a)) = linvT.row(a);
      auto u = w.row_space.block(0, s, r, added);
      u.setZero();
      for (const Workspace::Range& g : newRanges)
        u.middleRows(g.begin, g.end - g.begin).noalias() = jt.middleRows(g.begin, g.end - g.begin) * coef;
      smallest = std::numeric_limits<double>::infinity();
      for (int a = 0; a < added; ++a) smallest = std::min(smallest, work(a, a));
    }
    // The new rows are analytically orthogonal to W; round-off grows like eps |J̃| / σ, so
    // re-orthogonalise (densely; rare) when a kept singular value is small.
    if (smallest < 1e-3 && s > 0) {
      for (int c = 0; c < added; ++c) {
        auto col = w.row_space.col(s + c).head(r);
        auto proj = w.small_b.head(s + c);
        proj.noalias() = w.row_space.topLeftCorner(r, s + c).transpose() * col;
        col.noalias() -= w.row_space.topLeftCorner(r, s + c) * proj;
        col.normalize();
      }
      newRanges.clear();
      newRanges.push_back({0, r});
    }
    w.block_begin[blocks] = s;
    w.block_size[blocks] = added;
    ++blocks;
    s += added;
  }
  w.dq = w.dq0;
  if (maskMode)
    w.dq += z;
  else
    for (const Workspace::ColumnGroup& g : w.null_groups)
      w.dq.segment(g.row_begin, g.row_end - g.row_begin).noalias() +=
          w.nullspace.block(g.row_begin, g.col_begin, g.row_end - g.row_begin, g.col_end - g.col_begin) *
          z.segment(g.col_begin, g.col_end - g.col_begin);
}


}  // namespace embody::ik::detail
