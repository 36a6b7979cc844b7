// libFuzzer target: the text cloud reader. The first byte picks dim (0, 2 or 3).
#include "fuzz_common.hpp"
#include "softhd/io/cloud_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int dims[3] = {0, 2, 3};
  const int dim = dims[data[0] % 3];
  return softhd::fuzz::run(data + 1, size - 1, [dim](const std::string& bytes) {
    softhd::fuzz::check_cloud(softhd::parse_text_cloud(bytes, "fuzz.txt", dim));
  });
}
