#include "util/allocation_cap.h"

#include <atomic>
#include <cstdlib>
#include <new>

namespace clbdpt {

namespace {

std::atomic<size_t> g_cap{0};  // 0: none

}  // namespace

void* allocate(size_t size) {
    const size_t cap = g_cap.load(std::memory_order_relaxed);
    if (cap != 0 && size > cap) throw std::bad_alloc();
    for (;;) {
        if (void* p = std::malloc(size != 0 ? size : 1)) return p;
        std::new_handler handler = std::get_new_handler();
        if (!handler) throw std::bad_alloc();
        handler();
    }
}

AllocationCap::AllocationCap(size_t max_bytes) : previous_(g_cap.exchange(max_bytes)) {}
AllocationCap::~AllocationCap() { g_cap.store(previous_); }

}  // namespace clbdpt

// The replaceable global allocation functions ([new.delete]); the aligned forms keep the
// standard library's.
void* operator new(std::size_t size) { return clbdpt::allocate(size); }
void* operator new[](std::size_t size) { return clbdpt::allocate(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    try {
        return clbdpt::allocate(size);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
