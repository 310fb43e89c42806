#include "core/parallel.h"

#include <memory>

#include <tbb/global_control.h>
#include <tbb/info.h>

namespace pic {

namespace {
std::unique_ptr<tbb::global_control> gControl;
}

int workerCount() {
    return static_cast<int>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

void setWorkerCount(int threads) {
    if (threads <= 0) {
        gControl.reset();
        return;
    }
    gControl = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
}

}  // namespace pic
