// libFuzzer target: the PCD reader (ascii, binary and binary_compressed).
#include "fuzz_common.hpp"
#include "softhd/io/cloud_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return softhd::fuzz::run(data, size, [](const std::string& bytes) {
    std::vector<std::string> notes;
    softhd::fuzz::check_cloud(softhd::parse_pcd_cloud(bytes, "fuzz.pcd", &notes));
  });
}
