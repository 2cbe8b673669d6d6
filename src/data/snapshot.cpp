#include "data/snapshot.h"

namespace raypc {

const Field* Snapshot::find(const std::string& name) const
{
    for (const auto& f : fields)
        if (f.name == name)
            return &f;
    return nullptr;
}

Field* Snapshot::find(const std::string& name)
{
    for (auto& f : fields)
        if (f.name == name)
            return &f;
    return nullptr;
}

}  // namespace raypc
