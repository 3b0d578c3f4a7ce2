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
      const int lo = w.null_span[c].begin, hi = w.null_span[c].end;
      if (!w.null_groups.empty() && w.null_groups.back().row_begin == lo && w.null_groups.back().row_end == hi &&
          w.null_groups.back().col_end == c)
        w.null_groups.back().col_end = c + 1;
      else
        w.null_groups.push_back({c, c + 1, lo, hi, 0, 0});
    }
    for (Workspace::ColumnGroup& g : w.null_groups) {
      int begin = w.rows, end = 0;
      for (int d = g.row_begin; d < g.row_end; ++d) {
        begin = std::min(begin, w.dof_task_row_begin[d]);
        end = std::max(end, w.dof_task_row_end[d]);
      }
      g.task_row_begin = std::min(begin, end);
      g.task_row_end = end;
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
    else {  // the constrained dofs' block: J's rows that can be non-zero there only
      const int t0 = g.task_row_begin, tn = g.task_row_end - g.task_row_begin;
      dst.topRows(t0).setZero();
      dst.bottomRows(w.rows - g.task_row_end).setZero();
      dst.middleRows(t0, tn).noalias() =
          w.jacobian.block(t0, g.row_begin, tn, rows) * w.nullspace.block(g.row_begin, g.col_begin, rows, cols);
    }
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

namespace {

// One level of the fast pass: its rows, its support in reduced coordinates and J̃ there.
struct FastLevel {
  size_t k = 0;
  int first_row = 0, m = 0;
  const std::vector<int>* support = nullptr;
  const std::vector<Workspace::Range>* ranges = nullptr;
  int p = 0;            // support size
  bool gather = false;  // J̃ gathered on the support (else the block of J N over all r columns)
};

// The level's support (its recruited dofs in mask mode; in dense mode the columns of N that reach
// any of them) and J̃ on it: gathered (mask mode: J diag(mask) read straight from J), or the block
// of J N when the level reaches every reduced coordinate.
FastLevel gatherLevel(const Model::Level& level, size_t k, Workspace& w, int r) {
  const bool maskMode = w.mask_mode;
  FastLevel f;
  f.k = k;
  f.first_row = level.first_row;
  f.m = level.rows;
  if (!maskMode) denseSupport(w, w.level_ranges[k], r);
  f.support = maskMode ? &w.level_support[k] : &w.dense_support;
  f.ranges = maskMode ? &w.level_ranges[k] : &w.dense_support_ranges;
  f.p = static_cast<int>(f.support->size());
  f.gather = maskMode || f.p < r;
  if (f.gather) {
    auto g = w.gathered_j.topLeftCorner(f.m, f.p);
    for (int i = 0; i < f.p; ++i) {
      const int c = (*f.support)[i];
      if (!maskMode)
        g.col(i) = w.reduced_jacobian.col(c).segment(f.first_row, f.m);
      else if (w.rank == 0 || w.mask(c) != 0.0)  // no pinned dof: J̃ = J
        g.col(i) = w.jacobian.col(c).segment(f.first_row, f.m);
      else
        g.col(i).setZero();
    }
  }
  return f;
}

Eigen::Ref<const Eigen::MatrixXd> levelJacobian(const FastLevel& f, const Workspace& w, int r) {
  return f.gather ? Eigen::Ref<const Eigen::MatrixXd>(w.gathered_j.topLeftCorner(f.m, f.p))
                  : Eigen::Ref<const Eigen::MatrixXd>(w.reduced_jacobian.block(f.first_row, 0, f.m, r));
}

// J̃W block by block, over the rows the level shares with each block (marks the blocks touched).
template <typename JRows, typename JW>
void levelTimesW(const FastLevel& f, Workspace& w, const JRows& jRows, JW& jw, int blocks) {
  for (int b = 0; b < blocks; ++b) {
    auto jwb = jw.middleCols(w.block_begin[b], w.block_size[b]);
    jwb.setZero();
    bool touched = false;
    forEachOverlap(*f.ranges, w.block_ranges[b], [&](int lo, int hi) {
      addProduct(jwb, jRows.middleCols(lo, hi - lo), w.row_space.block(lo, w.block_begin[b], hi - lo, w.block_size[b]), 1.0);
      touched = true;
    });
    w.block_touched[b] = touched ? 1 : 0;
  }
}

// The damped step Δz = Ĵᵀ (G + λ² I)⁻¹ res (trust region applied), added to z.
template <typename JW, typename Z>
void levelStep(const FastLevel& f, Workspace& w, const SolveOptions& o, const Eigen::Ref<const Eigen::MatrixXd>& js,
               const JW& jw, const LevelDamping& d, int r, int blocks, Z& z) {
  const size_t k = f.k;
  const Eigen::MatrixXd& gram = w.level_gram[k];
  Eigen::VectorXd& y = w.level_y[k];
  y = w.level_res[k];
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
  if (f.gather) {
    auto jty = w.small_a.head(f.p);
    jty.noalias() = js.transpose() * y;
    dz.setZero();
    for (int i = 0; i < f.p; ++i) dz((*f.support)[i]) = jty(i);
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
  w.level_step[k].head(r) = dz;  // for the oscillation guard
  w.level_step_set[k] = 1;
}

// Ĵᵀ = J̃ᵀ - W (J̃W)ᵀ into `jt` (r x m), non-zero on the rows marked in w.row_mark; the marked rows
// as ranges into w.block_ranges[blocks] (the new block's rows).
template <typename JT, typename JW>
void projectedTranspose(const FastLevel& f, Workspace& w, const Eigen::Ref<const Eigen::MatrixXd>& js, const JW& jw,
                        JT& jt, int r, int blocks) {
  std::fill(w.row_mark.begin(), w.row_mark.begin() + r, 0);
  if (f.gather) {
    for (const Workspace::Range& g : *f.ranges) {
      jt.middleRows(g.begin, g.end - g.begin).setZero();
      std::fill(w.row_mark.begin() + g.begin, w.row_mark.begin() + g.end, 1);
    }
    for (int i = 0; i < f.p; ++i) jt.row((*f.support)[i]) = js.col(i).transpose();
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
  markedRanges(w.row_mark, r, w.block_ranges[blocks]);
}

// Projector update (undamped, rank-thresholded): appends an orthonormal basis of Ĵ's rows to W
// as block `blocks` (columns from s). Returns how many columns it added.
template <typename JT>
int appendLevelRows(const FastLevel& f, Workspace& w, const SolveOptions& o, const LevelDamping& d, const JT& jt,
                    int r, int s, int blocks) {
  const size_t k = f.k;
  const int m = f.m;
  std::vector<Workspace::Range>& newRanges = w.block_ranges[blocks];
  int added = 0;
  double smallest = 0.0;
  w.block_pivoted[blocks] = 0;
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
    w.block_pivoted[blocks] = 1;
    Eigen::MatrixXd& work = w.level_factor2[k];
    Eigen::VectorXi& perm = w.level_perm[k];
    added = detail::pivotedCholesky(w.level_gram[k], o.rank_tolerance * o.rank_tolerance, r - s, work, perm,
                                    w.level_factor2_inv[k]);
    if (added == 0) return 0;
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
  return added;
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
  w.level_step_reduced = !maskMode;
  std::fill(w.level_step_set.begin(), w.level_step_set.end(), 0);
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
  w.block_count = 0;
  for (size_t k = 0; k < model.levels.size(); ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w) || s >= r) continue;
    const FastLevel f = gatherLevel(level, k, w, r);
    const Eigen::Ref<const Eigen::MatrixXd> js = levelJacobian(f, w, r);
    const auto jRows = jFull.middleRows(f.first_row, f.m);
    auto jw = w.level_jw[k].leftCols(s);
    levelTimesW(f, w, jRows, jw, blocks);

    Eigen::VectorXd& res = w.level_res[k];  // the compensated error e_k - J_k Δq
    res = w.error.segment(f.first_row, f.m);
    res -= jdq0.segment(f.first_row, f.m);
    if (f.gather) {
      auto zs = w.small_b.head(f.p);
      for (int i = 0; i < f.p; ++i) zs(i) = z((*f.support)[i]);
      res.noalias() -= js * zs;
    } else {
      res.noalias() -= js * z;
    }
    Eigen::MatrixXd& gram = w.level_gram[k];  // lower triangle only: the kernels read just that
    gram.setZero();
    gram.selfadjointView<Eigen::Lower>().rankUpdate(js);
    if (s > 0) gram.selfadjointView<Eigen::Lower>().rankUpdate(jw, -1.0);
    const LevelDamping d = levelDamping(gram, w, k, o);
    levelStep(f, w, o, js, jw, d, r, blocks, z);

    if (static_cast<int>(k) == lastActive) break;  // nothing below needs this level's rows
    auto jt = w.level_cols.topLeftCorner(r, f.m);
    projectedTranspose(f, w, js, jw, jt, r, blocks);
    const int added = appendLevelRows(f, w, o, d, jt, r, s, blocks);
    if (added == 0) continue;
    w.block_begin[blocks] = s;
    w.block_size[blocks] = added;
    w.block_level[blocks] = static_cast<int>(k);
    w.block_count = ++blocks;
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
