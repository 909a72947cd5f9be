// Work split over threads, as OpenImageIO's parallel_image splits an image: tasks (bands of
// rows) are handed out one at a time from an atomic counter, so a slow band (a pole, a seam)
// does not hold up the others. Every task writes only its own output rows, so the result does
// not depend on the thread count or on which thread ran a task.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace envconv {

// Set (from any thread) to stop every running parallel_for at its next task: the run was
// interrupted (SIGINT, SIGTERM). Tasks already started finish; parallel_for then throws
// Cancelled. The Python side clears it once the kernel has returned.
inline std::atomic<bool> cancel_requested{false};

struct Cancelled : std::exception {
    const char* what() const noexcept override { return "cancelled"; }
};

inline void check_cancel() {
    if (cancel_requested.load(std::memory_order_relaxed)) throw Cancelled();
}

// Run body(task) for task in [0, tasks) on up to `threads` threads (the caller's included).
// The first exception thrown by a task is rethrown after every thread has finished.
template <typename Body>
void parallel_for(int64_t tasks, int threads, Body&& body) {
    int count = int(std::max<int64_t>(1, std::min<int64_t>(threads, tasks)));
    if (count <= 1) {
        for (int64_t t = 0; t < tasks; ++t) {
            check_cancel();
            body(t);
        }
        return;
    }
    std::atomic<int64_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_lock;
    auto worker = [&]() {
        try {
            for (int64_t t = next++; t < tasks; t = next++) {
                check_cancel();
                body(t);
            }
        } catch (...) {
            std::lock_guard<std::mutex> hold(failure_lock);
            if (!failure) failure = std::current_exception();
            next = tasks;
        }
    };
    std::vector<std::thread> pool;
    pool.reserve(count - 1);
    for (int k = 1; k < count; ++k) pool.emplace_back(worker);
    worker();
    for (auto& thread : pool) thread.join();
    if (failure) std::rethrow_exception(failure);
}

}  // namespace envconv
