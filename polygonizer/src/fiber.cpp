// glibc's fortified longjmp (_FORTIFY_SOURCE, a default of some distributions' compilers) refuses
// a jump to another stack, which is what a switch is.
#undef _FORTIFY_SOURCE
#include "fiber.h"

#include <cstdint>
#include <new>
#include <utility>

#include <sys/mman.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/common_interface_defs.h>
#endif

namespace cdp::detail {

namespace {

// AddressSanitizer's fiber interface (no-ops without it): before a switch, the stack switched to;
// after it, the stack switched from.
void start_switch([[maybe_unused]] void** fake_save, [[maybe_unused]] const void* bottom,
                  [[maybe_unused]] std::size_t size) {
#if defined(__SANITIZE_ADDRESS__)
  __sanitizer_start_switch_fiber(fake_save, bottom, size);
#endif
}
void finish_switch([[maybe_unused]] void* fake_save, [[maybe_unused]] const void** bottom_old,
                   [[maybe_unused]] std::size_t* size_old) {
#if defined(__SANITIZE_ADDRESS__)
  __sanitizer_finish_switch_fiber(fake_save, bottom_old, size_old);
#endif
}

}  // namespace

Fiber::Fiber(std::function<void()> body, std::size_t stack_bytes) : body_(std::move(body)) {
  const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const std::size_t stack = (stack_bytes + page - 1) / page * page;
  map_bytes_ = stack + page;
  map_ = mmap(nullptr, map_bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE | MAP_STACK, -1, 0);
  if (map_ == MAP_FAILED) {
    map_ = nullptr;
    throw std::bad_alloc();
  }
  // The lowest page faults: a stack overflow stops there instead of writing over other memory.
  if (mprotect(map_, page, PROT_NONE) != 0 || getcontext(&context_) != 0) {
    munmap(map_, map_bytes_);
    map_ = nullptr;
    throw std::bad_alloc();
  }
  context_.uc_stack.ss_sp = static_cast<char*>(map_) + page;
  context_.uc_stack.ss_size = stack;
  context_.uc_link = nullptr;  // the body never returns through it: switch_out(true) leaves
  // makecontext passes ints: the pointer in two halves.
  const auto self = reinterpret_cast<std::uintptr_t>(this);
  makecontext(&context_, reinterpret_cast<void (*)()>(&Fiber::entry), 2, static_cast<unsigned>(self >> 32),
              static_cast<unsigned>(self & 0xffffffffu));
}

Fiber::~Fiber() {
  // A fiber suspended for good keeps its frames' objects undestroyed (nothing unwinds them):
  // callers run their fibers to the end.
  if (map_) munmap(map_, map_bytes_);
}

void Fiber::entry(unsigned hi, unsigned lo) {
  auto* const self = reinterpret_cast<Fiber*>((static_cast<std::uintptr_t>(hi) << 32) | lo);
  finish_switch(nullptr, &self->caller_bottom_, &self->caller_size_);
  try {
    self->body_();
  } catch (...) {
    self->error_ = std::current_exception();
  }
  self->finished_ = true;
  self->switch_out(true);
}

void Fiber::resume() {
  start_switch(&caller_fake_, context_.uc_stack.ss_sp, context_.uc_stack.ss_size);
  // The first time through setcontext, which enters the body on its stack; after that, where
  // the body last suspended. Either way the fiber comes back by a jump to caller_.
  if (_setjmp(caller_) == 0) {
    if (!started_) {
      started_ = true;
      setcontext(&context_);
    }
    _longjmp(fiber_, 1);
  }
  finish_switch(caller_fake_, nullptr, nullptr);
  if (finished_ && error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void Fiber::suspend() { switch_out(false); }

void Fiber::switch_out(bool last) {
  // The fiber's fake stack is let go when it leaves for good (a null save).
  start_switch(last ? nullptr : &fiber_fake_, caller_bottom_, caller_size_);
  if (last || _setjmp(fiber_) == 0) _longjmp(caller_, 1);
  finish_switch(fiber_fake_, &caller_bottom_, &caller_size_);
}

}  // namespace cdp::detail
