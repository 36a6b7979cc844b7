// libFuzzer target: the scene parser. A 64 MiB memory limit keeps accepted meshes small
// enough for the fuzzer (larger ones are refused with a ResourceError, also a softhd::Error).
#include "fuzz_common.hpp"
#include "softhd/fe/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return softhd::fuzz::run(data, size, [](const std::string& bytes) {
    const softhd::fe::Scene s = softhd::fe::parse_scene(bytes, "fuzz.json", 64.0 * (1 << 20));
    if (s.dim() != 2 && s.dim() != 3) std::abort();
    if (!(s.control_lower <= s.control_upper)) std::abort();
  });
}
