// raypc: interactive visual analysis of mantle convection simulations.
#include "app/cli.h"
#include "core/system_memory.h"

int main(int argc, char** argv)
{
    // Only the executable restarts itself (it execs /proc/self/exe): inside Python that would be
    // the interpreter, so src/python calls raypc::app::run without this.
    raypc::restartWithTransparentHugePages(argv);
    return raypc::app::run(argc, argv);
}
