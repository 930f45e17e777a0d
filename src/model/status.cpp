#include <hmsm/status.h>

namespace hmsm {

const char* to_string(ErrorCode code) {
    switch (code) {
        case ErrorCode::ok: return "ok";
        case ErrorCode::invalid_argument: return "invalid argument";
        case ErrorCode::invalid_tree: return "invalid tree";
        case ErrorCode::io: return "i/o error";
        case ErrorCode::no_device: return "no device";
        case ErrorCode::device_error: return "device error";
        case ErrorCode::out_of_memory: return "out of memory";
        case ErrorCode::unsupported: return "unsupported";
        case ErrorCode::internal: return "internal error";
    }
    return "unknown error";
}

}  // namespace hmsm
