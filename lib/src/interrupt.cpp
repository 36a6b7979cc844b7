#include "softhd/interrupt.hpp"

#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "softhd/error.hpp"

namespace softhd {

namespace {
std::mutex g_mutex;
std::shared_ptr<const InterruptCheck> g_check;  // null: none
}  // namespace

InterruptCheck set_interrupt_check(InterruptCheck check) {
  auto next = check ? std::make_shared<const InterruptCheck>(std::move(check)) : nullptr;
  std::lock_guard<std::mutex> lock(g_mutex);
  std::shared_ptr<const InterruptCheck> previous = std::exchange(g_check, std::move(next));
  return previous ? *previous : InterruptCheck{};
}

void check_interrupt(const char* where) {
  std::shared_ptr<const InterruptCheck> check;
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    check = g_check;
  }
  if (check && (*check)()) throw Interrupted(std::string("interrupted ") + where);
}

}  // namespace softhd
