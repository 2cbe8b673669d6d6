// libFuzzer target: the VTK XML UnstructuredGrid reader (io/vtk_xml.h) on arbitrary bytes. Any
// input must give a Piece or one raypc::Error; never a crash, a hang or an allocation far beyond
// what the bytes can hold (run.sh caps RSS). A Piece it gives holds only finite float32 values and
// point indices within its points: what `raypc info` and the resampler take from it without
// checking again (a NaN in a point array crashed `raypc info`).
#include "core/error.h"
#include "io/vtk_xml.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    try {
        const raypc::io::vtk::Piece piece =
            raypc::io::vtk::parseVtu(std::string(reinterpret_cast<const char*>(data), size), "fuzz.vtu");
        const size_t points = piece.points.size() / 3;
        for (const auto& array : piece.pointData) {
            if (array.values.size() != points * size_t(array.components))
                __builtin_trap();
            for (const float v : array.values)
                if (!std::isfinite(v))
                    __builtin_trap();
        }
        for (const double p : piece.points)
            if (!std::isfinite(p))
                __builtin_trap();
        for (const auto index : piece.connectivity)
            if (index < 0 || size_t(index) >= points)
                __builtin_trap();
    } catch (const raypc::Error&) {
    }
    return 0;
}
