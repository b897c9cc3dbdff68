#pragma once
// How a call on the frame path turns down a bad argument (docs/engine.md, "Errors"): it records and writes
// nothing, says why through the device's log callback at LogLevel::Error, and returns false. No exception
// leaves such a call, and the message is formatted into a fixed buffer: refusing allocates nothing either.
#include <hemi/gpu/device.h>

#include <cstdarg>
#include <cstdio>

namespace hemi::render::detail
{

// The last refusal's message on this thread: what hemi's own tools (the views, which throw on bad input)
// put in their exception after a frame-path call refused.
inline char* last_refusal() noexcept
{
    thread_local char message[512] = "";
    return message;
}

// Logs "hemi: <call>: <format...>" and returns false, so that `return refuse(...);` ends the call.
[[gnu::format(printf, 3, 4)]] inline bool refuse(const gpu::Device& device, const char* call,
                                                 const char* format, ...) noexcept
{
    char* message = last_refusal();
    constexpr size_t kSize = 512;
    int n = std::snprintf(message, kSize, "hemi: %s: ", call);
    if (n < 0)
        n = 0;
    if (size_t(n) < kSize)
    {
        va_list args;
        va_start(args, format);
        std::vsnprintf(message + n, kSize - size_t(n), format, args);
        va_end(args);
    }
    device.log(gpu::LogLevel::Error, message);
    return false;
}

} // namespace hemi::render::detail
