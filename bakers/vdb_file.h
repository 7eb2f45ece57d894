// Writing OpenVDB files the bakers' way (private to bakers/: it includes OpenVDB): atomically,
// with the file's random UUID replaced by one derived from its content, so the same bake gives
// the same bytes.
#pragma once
#include <openvdb/openvdb.h>

#include <functional>
#include <string>
#include <vector>

namespace snow {

void writeVdbGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids);

// The same file, each grid made by its maker only when its turn comes, written and freed before
// the next is made: io::File::write needs every grid in memory at once, and a bake's snow grids
// side by side were its writer's peak. The bytes are io::File::write's of the same grids (the
// steps of io::Archive::write, in its order). Grid names must be unique and not empty.
using VdbGridMaker = std::function<openvdb::GridBase::Ptr()>;
void writeVdbGridsOneByOneAtomically(const std::string& path, const std::vector<VdbGridMaker>& makers);

}  // namespace snow
