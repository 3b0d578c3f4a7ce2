#pragma once
// The OpenXR two-call idiom: capacity 0 asks for the count; a too-small buffer is an error.
#include <openxr/openxr.h>

#include <cstddef>
#include <cstdint>

namespace embody::xr_runtime {

template <typename T, typename Fill>
XrResult twoCall(uint32_t capacity, uint32_t* count, T* out, size_t n, Fill fill) {
  if (!count) return XR_ERROR_VALIDATION_FAILURE;
  *count = static_cast<uint32_t>(n);
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < n) return XR_ERROR_SIZE_INSUFFICIENT;
  if (!out) return XR_ERROR_VALIDATION_FAILURE;
  for (size_t i = 0; i < n; ++i) fill(out + i, i);
  return XR_SUCCESS;
}

}  // namespace embody::xr_runtime
