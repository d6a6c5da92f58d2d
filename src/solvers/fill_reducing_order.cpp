#include "fill_reducing_order.hpp"

#include <cholmod.h>

#include "cholmod_common.hpp"

namespace indentsim {

static_assert(sizeof(SuiteSparse_long) == sizeof(std::int64_t), "CHOLMOD's long interface holds 64-bit indices");

namespace {

// A symmetric pattern (CSC, both triangles) as CHOLMOD reads it: the upper triangle stands for
// the whole.  The arrays stay the caller's.
cholmod_sparse symmetric_pattern(std::vector<SuiteSparse_long>& column_start, std::vector<SuiteSparse_long>& row_index) {
  cholmod_sparse pattern{};
  pattern.nrow = pattern.ncol = column_start.size() - 1;
  pattern.nzmax = static_cast<std::size_t>(column_start.back());
  pattern.p = column_start.data();
  pattern.i = row_index.data();
  pattern.stype = 1;
  pattern.itype = CHOLMOD_LONG;
  pattern.xtype = CHOLMOD_PATTERN;
  pattern.dtype = CHOLMOD_DOUBLE;
  pattern.sorted = 1;
  pattern.packed = 1;
  return pattern;
}

struct Ordering {
  std::vector<std::int64_t> order;  // empty: CHOLMOD failed
  double factor_nonzeros = 0.0;     // nnz(L) of the Cholesky factor in this order
};

// CHOLMOD's nested dissection (METIS bisections, constrained minimum degree on the parts),
// postordered, or the `given` order; with the fill it leaves.  On the near fields of plastic runs
// nested dissection leaves less fill than AMD as the mesh is refined -- nnz(L+U) 0.78 M against
// 0.86 M and 17% fewer flops at 11 000 unknowns (deep_plastic.toml, contact_nodes 30); refactor
// and solves take 7% less of the whole run there and 14% at contact_nodes 48 -- because a 2-D
// mesh's separators are what nested dissection is made for.
Ordering analysed_order(std::vector<SuiteSparse_long> column_start, std::vector<SuiteSparse_long> row_index,
                        std::vector<std::int64_t> given = {}) {
  const auto n = static_cast<std::size_t>(column_start.size() - 1);
  CholmodCommon cholmod;
  cholmod_common* cm = &cholmod.common;
  cm->nmethods = 1;
  cm->method[0].ordering = given.empty() ? CHOLMOD_NESDIS : CHOLMOD_GIVEN;
  cm->postorder = 1;
  cholmod_sparse pattern = symmetric_pattern(column_start, row_index);
  cholmod_factor* symbolic = given.empty() ? analyze_serialized(&pattern, cm)
                                           : cholmod_l_analyze_p(&pattern, given.data(), nullptr, 0, cm);
  if (!symbolic) return {};
  const auto* perm = static_cast<const SuiteSparse_long*>(symbolic->Perm);
  Ordering result{std::vector<std::int64_t>(perm, perm + n), cm->lnz};
  cholmod_l_free_factor(&symbolic, cm);
  return result;
}

}  // namespace

// Why the dense block is tried last, dissected apart: a condensed near field's interface unknowns
// are coupled all to all (K_red's dense block, docs/DESIGN.md §7), so in any order they end up in
// one dense trailing block of the factors.  METIS, bisecting the whole graph, usually cuts through
// that clique instead, and every separator it puts there is coupled to the rest of the clique.
// Dissecting the sparse remainder alone and appending the block left less fill on every shipped
// plastic case: KLU's flops -12% (deep_plastic.toml, contact_nodes 24), -13% (48), -19%
// (Berkovich cone), its nnz(L+U) -5 to -8%; CHOLMOD's flops -40% and nnz(L) -21% at
// contact_nodes 48 (where its own choice was AMD).  On a near field little wider than its
// interface the whole graph's dissection can win (4% less fill on a test's 30 x 26 elements), so
// both are analysed and the one with the smaller Cholesky factor is kept.  That is done once per
// Newton system and costs about twice the whole graph's dissection alone (123 ms against 68 ms at
// 27 559 unknowns, half of one KLU refactorization there).
std::vector<std::int64_t> fill_reducing_order(const std::vector<std::int64_t>& column_start,
                                              const std::vector<std::int64_t>& row_index,
                                              const std::vector<std::int64_t>& dense_block) {
  Ordering whole = analysed_order(column_start, row_index);
  if (dense_block.empty()) return std::move(whole.order);
  const auto n = static_cast<std::size_t>(column_start.size() - 1);
  // The sparse remainder, renumbered 0, 1, ... in the pattern's order (-1: in the dense block).
  std::vector<std::int64_t> renumbered(n, 0), remainder;
  for (const std::int64_t d : dense_block) renumbered[static_cast<std::size_t>(d)] = -1;
  for (std::size_t j = 0; j < n; ++j)
    if (renumbered[j] >= 0) {
      renumbered[j] = static_cast<std::int64_t>(remainder.size());
      remainder.push_back(static_cast<std::int64_t>(j));
    }
  std::vector<std::int64_t> block_last;
  block_last.reserve(n);
  if (!remainder.empty()) {
    std::vector<SuiteSparse_long> sub_start{0}, sub_rows;
    for (const std::int64_t j : remainder) {
      for (std::int64_t p = column_start[j]; p < column_start[j + 1]; ++p)
        if (renumbered[row_index[p]] >= 0) sub_rows.push_back(renumbered[row_index[p]]);
      sub_start.push_back(static_cast<SuiteSparse_long>(sub_rows.size()));
    }
    const Ordering sub = analysed_order(std::move(sub_start), std::move(sub_rows));
    if (sub.order.empty()) return std::move(whole.order);
    for (const std::int64_t k : sub.order) block_last.push_back(remainder[k]);
  }
  block_last.insert(block_last.end(), dense_block.begin(), dense_block.end());
  // Analysed as given, postordered (which keeps the block last: it holds the root of the tree).
  Ordering blocked = analysed_order(column_start, row_index, std::move(block_last));
  if (blocked.order.empty()) return std::move(whole.order);
  if (whole.order.empty() || blocked.factor_nonzeros < whole.factor_nonzeros) return std::move(blocked.order);
  return std::move(whole.order);
}

}  // namespace indentsim
