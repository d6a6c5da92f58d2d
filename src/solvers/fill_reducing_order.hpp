#pragma once
// The fill-reducing order of a Newton system's pattern, for the sparse direct solvers (private to
// the library): KLU analyses with it, CHOLMOD factors in it.
#include <cstdint>
#include <vector>

namespace indentsim {

/// A permutation of the unknowns of a symmetric pattern (CSC, every column's rows sorted, both
/// triangles stored), postordered: CHOLMOD's nested dissection (METIS bisections, constrained
/// minimum degree on the parts) of the whole pattern, or -- when `dense_block` (unknowns coupled
/// all to all) is given and this leaves a smaller Cholesky factor -- the nested dissection of the
/// unknowns outside the block followed by the block.  Empty if CHOLMOD fails.
std::vector<std::int64_t> fill_reducing_order(const std::vector<std::int64_t>& column_start,
                                              const std::vector<std::int64_t>& row_index,
                                              const std::vector<std::int64_t>& dense_block);

}  // namespace indentsim
