#include "vkloc/core/status.hpp"

#include "vkloc/core/text.hpp"

namespace vkloc {

const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return "invalid argument";
    case ErrorCode::kNotFound:
      return "not found";
    case ErrorCode::kIoError:
      return "i/o error";
    case ErrorCode::kMalformedInput:
      return "malformed input";
    case ErrorCode::kUnsupported:
      return "unsupported";
    case ErrorCode::kNoDevice:
      return "no device";
    case ErrorCode::kGpuError:
      return "gpu error";
  }
  return "unknown error";
}

Error makeError(ErrorCode code, std::string_view message) { return Error{code, text::oneLine(message)}; }

}  // namespace vkloc
