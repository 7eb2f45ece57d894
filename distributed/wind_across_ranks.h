// One wind state's fields on a rank's local grid, solved there: the bytes of the whole grid's
// solve (precompute/wind.h) without the whole grid on any rank.
//
// Where the free stream keeps one direction on every cell (the sign of each component the same
// everywhere, as W_venturi = (1 + k_venturi A) W_d keeps it), the upwind graph has no loops: a
// cell's W_z and W_sz are a function of its upwind neighbours' final values alone, which one
// sweep in the stream's order gives the single process. Across ranks each sweeps its owned cells
// in that order and refreshes its halo, round after round, until a round moves no cell on any
// rank: a fixed point of the same equations, which a loop-free graph has once, so the same
// doubles. A round brings the final values one subdomain further downwind: columns + rows rounds
// at most, and one that moves nothing.
#pragma once
#include "communicator.h"
#include "decomposition.h"
#include "precompute/wind.h"

namespace snow::dist {

// The fields of `state` on d.local(comm.rank()) and their loading (windLoading's), with the
// single process's statistics (its iterations: one sweep to the fixed point and one that moves
// nothing). False, on every rank alike, where the free stream turns somewhere (its components
// take both signs): the graph may have loops and the whole grid's solve is the reference.
bool solveWindOnLocalGrid(const Communicator& comm, const Decomposition& d, const Grid<float>& altitude, const Grid<uint8_t>& valid,
                          const GridSpec& spec, const WindState& state, const ModelParameters& params, const WindSolverOptions& options,
                          WindField& out, Grid<float>& loading);

}  // namespace snow::dist
