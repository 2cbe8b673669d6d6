// libFuzzer target: the VTK XML UnstructuredGrid reader (io/vtk_xml.h) on arbitrary bytes. Any
// input must give a Piece or one raypc::Error; never a crash, a hang or an allocation far beyond
// what the bytes can hold (run.sh caps RSS).
#include "core/error.h"
#include "io/vtk_xml.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    try {
        (void)raypc::vtk::parseVtu(std::string(reinterpret_cast<const char*>(data), size), "fuzz.vtu");
    } catch (const raypc::Error&) {
    }
    return 0;
}
