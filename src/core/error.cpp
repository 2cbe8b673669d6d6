#include "core/error.h"

#include <cstdio>
#include <cstdlib>

namespace raypc::detail {

void checkFailed(const char* file, int line, const char* expr, const std::string& operands)
{
    std::fprintf(stderr, "raypc: internal check failed at %s:%d: %s%s%s\n", file, line, expr,
                 operands.empty() ? "" : " with ", operands.c_str());
    std::abort();
}

}  // namespace raypc::detail
