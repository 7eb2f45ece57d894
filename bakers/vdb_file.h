// Writing OpenVDB files the bakers' way (private to bakers/: it includes OpenVDB): atomically,
// with the file's random UUID replaced by one derived from its content, so the same bake gives
// the same bytes.
#pragma once
#include <openvdb/openvdb.h>

#include <string>

namespace snow {

void writeVdbGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids);

}  // namespace snow
