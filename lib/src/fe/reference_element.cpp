#include "softhd/fe/reference_element.hpp"

#include "softhd/error.hpp"

namespace softhd::fe {

CellType cell_type(int dim, int order, bool simplex) {
  if ((dim != 2 && dim != 3) || (order != 1 && order != 2))
    throw InvalidArgument("cell type: need dimension 2 or 3 and order 1 or 2, got dimension " +
                          std::to_string(dim) + " and order " + std::to_string(order));
  if (dim == 2) {
    if (simplex) return order == 1 ? CellType::kTri3 : CellType::kTri6;
    return order == 1 ? CellType::kQuad4 : CellType::kQuad9;
  }
  if (simplex) return order == 1 ? CellType::kTet4 : CellType::kTet10;
  return order == 1 ? CellType::kHex8 : CellType::kHex27;
}

}  // namespace softhd::fe
