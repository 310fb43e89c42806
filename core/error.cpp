#include "core/error.h"

namespace pic {

const char* toString(ErrorCode code) {
    switch (code) {
    case ErrorCode::InvalidInput: return "invalid input";
    case ErrorCode::NotFound: return "not found";
    case ErrorCode::Corrupt: return "corrupt";
    case ErrorCode::Unsupported: return "unsupported";
    case ErrorCode::Io: return "i/o error";
    case ErrorCode::Internal: return "internal error";
    }
    return "error";
}

}  // namespace pic
