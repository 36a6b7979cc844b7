// libFuzzer target: the PLY reader (ascii and binary little-endian).
#include "fuzz_common.hpp"
#include "softhd/io/cloud_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return softhd::fuzz::run(data, size, [](const std::string& bytes) {
    softhd::fuzz::check_cloud(softhd::parse_ply_cloud(bytes, "fuzz.ply"));
  });
}
