#pragma once
/// Data-parallel loops over both cores (oneTBB). Every loop body writes only its own
/// outputs, so results do not depend on scheduling and bakes stay byte-identical.

#include <cstddef>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace pic {

/// Calls body(i) for i in [begin, end) on all worker threads; grain = indices per task.
template <class Body>
void parallelFor(size_t begin, size_t end, Body&& body, size_t grain = 64) {
    if (end <= begin) return;
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) body(i);
                      });
}

/// Calls body(rangeBegin, rangeEnd) on disjoint chunks covering [begin, end).
template <class Body>
void parallelForChunks(size_t begin, size_t end, Body&& body, size_t grain = 256) {
    if (end <= begin) return;
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

/// Number of worker threads loops use.
int workerCount();

/// Limits worker threads for the rest of the process (0 = all cores).
void setWorkerCount(int threads);

}  // namespace pic
