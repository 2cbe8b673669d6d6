// Errors and invariant checks.
//
// Expected failures (bad file, wrong option, malformed message) throw raypc::Error
// with a message that names the thing, what was found and what was expected.
// Broken invariants are programming errors: RAYPC_CHECK aborts with the operands.
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace raypc {

// The one project error type; caught at the edges (main, a WebSocket handler,
// a worker thread) and reported as one line.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

template <typename... Args>
[[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args)
{
    throw Error(fmt::format(format, std::forward<Args>(args)...));
}

namespace detail {
[[noreturn]] void checkFailed(const char* file, int line, const char* expr, const std::string& operands);
}  // namespace detail

}  // namespace raypc

#define RAYPC_CHECK(cond)                                                              \
    do {                                                                               \
        if (!(cond)) [[unlikely]]                                                      \
            ::raypc::detail::checkFailed(__FILE__, __LINE__, #cond, std::string());    \
    } while (false)

#define RAYPC_CHECK_OP(a, op, b)                                                       \
    do {                                                                               \
        const auto& raypcA_ = (a);                                                     \
        const auto& raypcB_ = (b);                                                     \
        if (!(raypcA_ op raypcB_)) [[unlikely]]                                        \
            ::raypc::detail::checkFailed(__FILE__, __LINE__, #a " " #op " " #b,         \
                                         fmt::format("{} vs {}", raypcA_, raypcB_));   \
    } while (false)

#define RAYPC_CHECK_EQ(a, b) RAYPC_CHECK_OP(a, ==, b)
#define RAYPC_CHECK_LT(a, b) RAYPC_CHECK_OP(a, <, b)
#define RAYPC_CHECK_LE(a, b) RAYPC_CHECK_OP(a, <=, b)
#define RAYPC_CHECK_GE(a, b) RAYPC_CHECK_OP(a, >=, b)
