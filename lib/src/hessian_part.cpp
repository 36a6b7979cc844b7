// The names of HessianPart (softhd/hessian_part.hpp).

#include "softhd/hessian_part.hpp"

#include "softhd/enum_names.hpp"

namespace softhd {

namespace {
constexpr EnumNames<HessianPart, 2> kHessianPartNames{
    {{HessianPart::full, "full"}, {HessianPart::gauss_newton, "gauss_newton"}}};
}  // namespace

std::string to_string(HessianPart part) { return enum_name(kHessianPartNames, part); }

HessianPart hessian_part_from_string(const std::string& name, const std::string& what) {
  return enum_from_name(kHessianPartNames, name, what);
}

}  // namespace softhd
