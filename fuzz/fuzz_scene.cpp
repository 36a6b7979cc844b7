// libFuzzer target: the scene parser. A 64 MiB memory limit keeps accepted meshes small
// enough for the fuzzer (larger ones are refused with a ResourceError, also a softhd::Error).
#include "fuzz_common.hpp"
#include "softhd/control/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return softhd::fuzz::run(data, size, [](const std::string& bytes) {
    const softhd::Scene s = softhd::parse_scene(bytes, "fuzz.json", 64.0 * (1 << 20));
    if (s.body.dim() != 2 && s.body.dim() != 3) std::abort();
    if (!(s.body.control_lower <= s.body.control_upper)) std::abort();
  });
}
