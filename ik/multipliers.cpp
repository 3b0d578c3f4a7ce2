// The pinned rows' lexicographic multipliers (the warm active set's release test, docs/ik.md):
// what level k's remaining error pushes each pinned row with, once the forces the levels above k
// can take are taken by them.
#include <Eigen/SVD>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

// g -= J_kᵀ x over the dofs level k recruits (J_k is zero on every other column).
template <typename X>
void subtractLevelTransposed(Workspace& w, size_t k, const Model::Level& level, const X& x, Eigen::VectorXd& g) {
  const auto j = w.jacobian.middleRows(level.first_row, level.rows);
  for (const Workspace::Range& c : w.level_ranges[k])
    g.segment(c.begin, c.end - c.begin).noalias() -= j.middleCols(c.begin, c.end - c.begin).transpose() * x;
}

// Fast path. W (row_space, r x s) holds the higher levels' orthonormal rows in reduced
// coordinates, one block per level j, and each level's J̃_j = J_j N satisfies
//   J̃_j = L_j U_jᵀ + (J̃_j W_<j) W_<jᵀ        (U_j its block of W, L_j the Cholesky factor of its G,
//                                              J̃_j W_<j kept in level_jw[j])
// (a rank-deficient level: the same for the rows I its pivoted Cholesky picked, L_II⁻ᵀ kept in
// level_inverse[j]). So J̃_Hᵀ λ = W Wᵀ g̃ is block upper triangular: solved block by block from
// the last higher level up.
void subtractHigherForcesFast(const Model& model, Workspace& w, size_t k, Eigen::VectorXd& g) {
  int blocks = 0;
  while (blocks < w.block_count && w.block_level[static_cast<size_t>(blocks)] < static_cast<int>(k)) ++blocks;
  if (blocks == 0) return;
  const int r = w.mask_mode ? w.n : w.null_dim;
  auto reduced = w.warm_reduced.head(r);  // g̃ = Nᵀ g
  if (w.mask_mode) {
    reduced = g.cwiseProduct(w.mask);
  } else {
    for (const Workspace::ColumnGroup& c : w.null_groups) {
      if (c.col_begin >= r) break;
      const int rows = c.row_end - c.row_begin, cols = c.col_end - c.col_begin;
      if (rows == 1 && cols == 1)  // a free dof's unit column: no product call for one term
        reduced(c.col_begin) = w.nullspace(c.row_begin, c.col_begin) * g(c.row_begin);
      else
        reduced.segment(c.col_begin, cols).noalias() =
            w.nullspace.block(c.row_begin, c.col_begin, rows, cols).transpose() * g.segment(c.row_begin, rows);
    }
  }
  const int s = w.block_begin[static_cast<size_t>(blocks - 1)] + w.block_size[static_cast<size_t>(blocks - 1)];
  auto t = w.small_b.head(s);  // Wᵀ g̃, then what is left of it for the blocks above
  t.noalias() = w.row_space.topLeftCorner(r, s).transpose() * reduced;
  for (int b = blocks; b-- > 0;) {
    const auto bi = static_cast<size_t>(b);
    const size_t j = static_cast<size_t>(w.block_level[bi]);
    const Model::Level& level = model.levels[j];
    const int m = level.rows, c0 = w.block_begin[bi], added = w.block_size[bi];
    auto lambda = w.warm_force.segment(level.first_row, m);
    if (!w.block_pivoted[bi]) {  // L_jᵀ λ = t_b
      lambda = t.segment(c0, added);
      w.level_factor[j].topLeftCorner(m, m).triangularView<Eigen::Lower>().transpose().solveInPlace(lambda);
    } else {  // λ_I = L_II⁻ᵀ t_b, the other rows 0
      auto picked = w.small_a.head(added);
      picked.noalias() = w.level_inverse[j].topLeftCorner(added, added) * t.segment(c0, added);
      lambda.setZero();
      for (int i = 0; i < added; ++i) lambda(w.level_perm[j](i)) = picked(i);
    }
    if (c0 > 0) t.head(c0).noalias() -= w.level_jw[j].leftCols(c0).transpose() * lambda;
    subtractLevelTransposed(w, j, level, lambda, g);
  }
}

// Reference path: the same back-substitution in full coordinates, from each higher level's SVD
// of Ĵ_j = J_j P_j (its row space: the right singular vectors kept by the projector update).
void subtractHigherForcesReference(const Model& model, Workspace& w, size_t k, const SolveOptions& o,
                                   Eigen::VectorXd& g) {
  Eigen::VectorXd& projected = w.warm_reduced;  // P0 g, then what is left of it
  projected.noalias() = w.projector0 * g;
  Eigen::VectorXd& force = w.tmp_n2;
  for (size_t j = k; j-- > 0;) {
    const Model::Level& level = model.levels[j];
    if (!levelActive(level, w)) continue;
    const auto& svd = w.level_svd[j];
    const auto& sv = svd.singularValues();
    auto lambda = w.warm_force.segment(level.first_row, level.rows);
    lambda.setZero();
    for (Eigen::Index i = 0; i < sv.size(); ++i)
      if (sv(i) > o.rank_tolerance) lambda += (svd.matrixV().col(i).dot(projected) / sv(i)) * svd.matrixU().col(i);
    force.noalias() = w.jacobian.middleRows(level.first_row, level.rows).transpose() * lambda;
    g -= force;
    projected.noalias() -= w.projector0 * force;
  }
}

}  // namespace

// With r_k = e_k - J_k Δq level k's remaining (weighted, clamped) error and g = J_kᵀ r_k, the
// multipliers of the active rows A = F Bᵀ for level k's problem (its error, with the active rows
// and the levels above held) solve Aᵀ μ + Σ_{j<k} J_jᵀ λ_j = g. The λ_j take the part of g the
// higher levels' rows can take (their row space in the null space of A); μ = F⁻ᵀ Bᵀ (g - Σ J_jᵀ λ_j).
// Only the carried rows' μ are needed; F⁻ᵀ is upper triangular and they come last, so their
// block of F is enough. μ_p > 0: level k pushes row p outward (the bound holds it); μ_p < 0:
// level k pulls it inside.
void carriedMultipliers(const Model& model, Workspace& w, size_t k, const SolveOptions& o) {
  const Model::Level& level = model.levels[k];
  const auto j = w.jacobian.middleRows(level.first_row, level.rows);
  auto residual = w.warm_residual.head(level.rows);
  residual = w.error.segment(level.first_row, level.rows);
  // J_k is zero outside the dofs the level recruits: its products run over those ranges only.
  const std::vector<Workspace::Range>& dofs = w.level_ranges[k];
  for (const Workspace::Range& c : dofs)
    residual.noalias() -= j.middleCols(c.begin, c.end - c.begin) * w.dq.segment(c.begin, c.end - c.begin);
  Eigen::VectorXd& g = w.warm_gradient;
  g.setZero();
  for (const Workspace::Range& c : dofs)
    g.segment(c.begin, c.end - c.begin).noalias() = j.middleCols(c.begin, c.end - c.begin).transpose() * residual;
  w.warm_gradient_norm = g.norm();
  if (o.path == Path::Fast)
    subtractHigherForcesFast(model, w, k, g);
  else
    subtractHigherForcesReference(model, w, k, o, g);
  const int c = w.carried_count, first = w.eq_rank;
  auto mu = w.warm_multiplier.head(c);
  mu.noalias() = w.basis.middleCols(first, c).transpose() * g;
  w.factor.block(first, first, c, c).triangularView<Eigen::Lower>().transpose().solveInPlace(mu);
}

}  // namespace embody::ik::detail
