// libFuzzer target: the checkpoint readers. The first byte picks the log (even) or its
// states file (odd); a states file that parses is also attached to a small fixed log.
#include "fuzz_common.hpp"
#include "softhd/control/run_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool states = data[0] & 1;
  return softhd::fuzz::run(data + 1, size - 1, [states](const std::string& bytes) {
    if (!states) {
      const softhd::RunLog log = softhd::parse_run_log(bytes, "fuzz.bin");
      for (const softhd::LoggedEvaluation& e : log.evaluations)
        if (e.x.size() == 0 || !e.x.allFinite()) std::abort();
      return;
    }
    std::uint64_t run_id = 0;
    softhd::RunSnapshot s = softhd::parse_run_states(bytes, "fuzz.states", &run_id);
    if (s.evaluations < 0 || s.iterations < 0 || s.iterations > s.evaluations) std::abort();
    softhd::RunLog log;
    log.run_id = run_id;
    log.evaluations.resize(3);
    softhd::attach_states(log, run_id, std::move(s), "fuzz.states");
    if (log.evaluations.size() != static_cast<std::size_t>(log.snapshot.evaluations)) std::abort();
  });
}
