#pragma once
// Method tree: the kernel sums of pair_kernel.hpp with a guaranteed relative error τ
// (internal; the tests include this header to check the guarantee sum by sum).
//
// Single-tree traversal over the source points of one pass, per outer point o,
// depth first, nearer child first. A node whose box does not contain o (distance
// R_min > 0 from o, farthest corner R_max) may be replaced by one term at the
// centroid x_c of its (effective) weights, k(r) = (c/(r+ε))^α, t = 1/(r+ε):
//     S ≈ W k(|o−x_c|),    G ≈ W k t (o−x_c)/|o−x_c|            (the same for H, G2)
// with rigorous error bounds (k, t decrease in r, so their sup over the box is at R_min):
//     |ΔS| ≤ min( ½ Σ w|x−x_c|² · sup‖∇²k‖ ,  W (k(R_min) − k(R_max)) )
//          sup‖∇²k‖ = α k t · max((α+1) t, 1/R_min)               at R_min
//     ‖ΔG‖ ≤ min( ½ Σ w|x−x_c|² · sup‖∇²F‖ ,  2 W k(R_min) t(R_min) )
//          F = k t u = −∇_o k/α, ‖∇²F[δ,δ]‖ ≤ (1/α)(|k'''| + (2/√3)|k'' − k'/r|/r)|δ|²
//          = k [ (α+1)(α+2) t³ + (2/√3) ((α+1) t² + t/r)/r ] |δ|²      at R_min
// (first-order terms vanish about the centroid; the interval bound holds because the
// exact node sum and the one-term value both lie in [W k(R_max), W k(R_min)]).
// Leaves that are not approximated are summed exactly with pair_sums.
//
// Guarantee. For each sum separately the traversal keeps `low`, a lower bound of the
// exact sum (exact leaf sums plus W k(R_max) of approximated nodes; all terms are ≥ 0),
// and `spent`, the sum of the error bounds of the approximations made. A node is
// approximated only if spent + err ≤ τ · low · share, share = (mass done)/(total mass)
// ≤ 1. `low` only grows, so at the end
//     |S − S_exact| ≤ spent ≤ τ · S_exact,   ‖G − G_exact‖ ≤ τ · Σ‖terms of G‖,
// likewise for H and G2 — up to floating-point rounding of the sums themselves
// (a few ulps times the number of terms added). For the vector sums the bound is
// relative to the sum of the norms of the terms, Gm = Σ_{r>0} w p t (G itself may cancel).
//
// Inner-scaled sums (kInner) carry a per-point scale c_n: a node uses C = max c_n and the
// effective weights h_n (c_n/C)^α, so the same bounds apply with c → C.

#include <cstdint>

#include "kd_tree.hpp"
#include "pair_kernel.hpp"

namespace softhd::detail {

/// One pass's sources for method tree. Arrays of `src` are in tree order.
struct TreePass {
  const KdTree* tree = nullptr;
  PairSources src;
  const NodeMoments* outer = nullptr;  ///< moments of src.weight (kOuterSum, kOuterGrad)
  const NodeMoments* inner = nullptr;  ///< moments of src.coef with scales src.scale (kInner)
};

/// The sums of pair_sums for outer point `o` (scale c_o) within relative tolerance τ as
/// above; also fills Gm/G2m with lower bounds of the magnitude sums. `evaluations`
/// grows by one per kernel evaluation made: one per source point summed exactly, one
/// per node approximation. No allocation.
PairSums tree_sums(const double* o, double c_o, const TreePass& pass, const KernelPower& power,
                   double eps, double tau, unsigned flags, std::int64_t& evaluations);

}  // namespace softhd::detail
