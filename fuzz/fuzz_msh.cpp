// libFuzzer target: the Gmsh MSH reader (4.1 ASCII and binary, 2.2 ASCII) and its scan of
// the counts.
#include <cmath>

#include "fuzz_common.hpp"
#include "softhd/io/msh.hpp"

namespace {

// Aborts (a finding) unless every index of the parsed file is in range and every
// coordinate and value is finite.
void check_msh(const softhd::io::MshFile& m) {
  const auto n = m.nodes.rows();
  if (m.nodes.cols() != 3 || !m.nodes.allFinite() || m.node_tags.size() != std::size_t(n))
    std::abort();
  for (const auto& b : m.blocks) {
    if (b.nodes.cols() != softhd::io::gmsh_nodes_per_element(b.gmsh_type) ||
        b.dim != softhd::io::gmsh_element_dim(b.gmsh_type) ||
        b.element_tags.size() != std::size_t(b.nodes.rows()))
      std::abort();
    if (b.nodes.size() > 0 && (b.nodes.minCoeff() < 0 || b.nodes.maxCoeff() >= n)) std::abort();
  }
  for (const auto& d : m.data) {
    if (d.values.rows() != static_cast<Eigen::Index>(d.tags.size()) ||
        d.values.cols() != d.components || !d.values.allFinite())
      std::abort();
    for (std::int64_t t : d.tags) {
      if (!d.per_element && (t < 0 || t >= n)) std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return softhd::fuzz::run(data, size, [](const std::string& bytes) {
    softhd::io::MshCounts counts;  // the scan before the parse (read_msh's memory check)
    const bool scanned = softhd::io::scan_msh_counts(bytes, &counts);
    const softhd::io::MshFile m = softhd::io::parse_msh(bytes, "fuzz.msh");
    check_msh(m);
    if (scanned && counts.nodes != static_cast<std::size_t>(m.nodes.rows())) std::abort();
  });
}
