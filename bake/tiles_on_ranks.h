// Outputs across ranks written where their cells are (docs/distributed.md, Outputs): under
// [outputs.tiles], the ranks' subdomains are cut on tile starts, so each rank's local grid holds
// every cell of the tiles that start in its subdomain, and each rank writes those tiles from its
// own cells (a resampled image's tiles, whose pixels read cells further out, from those cells
// gathered from their owners). A whole file is rank 0's, each gathered from the ranks one at a
// time (OutputWriter::untiledWindow). A layer's range ("own", "season") is combined over the ranks, and rank 0 merges the
// files every rank listed into one manifest in the single process's order. The same bytes as one
// process, and no rank holds the whole grid for the outputs.
#pragma once
#include <optional>
#include <string>

#include "bakers/output_sink.h"
#include "bakers/output_writer.h"
#include "distributed/communicator.h"
#include "distributed/decomposition.h"
#include "scene/scene.h"

namespace snow {

// Why the ranks cannot write their own tiles and rank 0 the whole files of the scene's outputs
// (rank 0 then gathers the whole grid and writes every file), naming the key; empty when they
// can, as far as the scene says (the grid must also split into bands of whole tiles:
// decompositionOnTiles).
std::string whyRankZeroWritesEveryFile(const Scene& scene);

// The ranks' subdomains cut on the starts of the scene's tiles of a grid of `spec`'s size (the
// balanced splits without [outputs.tiles]), where whyRankZeroWritesEveryFile is empty, the tiles
// can be shared and no rank's local grid is the whole grid (the writers tell a rank's window from
// an image every rank holds whole by its size); else nullopt. The halo is `minHalo`, or wider
// where the tiles' overlap and the next cell need it.
std::optional<dist::Decomposition> decompositionOnTiles(const Scene& scene, const GridSpec& spec, int ranks, int minHalo);

// The scene a rank writing its tiles is predicted from (the memory guard, memory_model.h): its
// resampled images (outputs.resize, the displacement maps) are the window of pixels of the tiles
// starting in its subdomain of ownedWidth x ownedHeight cells (OutputWriter::writtenPixels): at
// most the subdomain's share of the image, a tile past it and the normal map's pixel each way.
Scene sceneOfTheRanksTiles(const Scene& scene, const GridSpec& whole, int ownedWidth, int ownedHeight);

// Points `sources` at this rank's tiles of decomposition `d`: its local grid's state, the tiles
// starting in its subdomain, a layer's range combined over the ranks, and the cells a resampled
// image's tiles read gathered from their owners.
void shareTheTiles(OutputSources& sources, const dist::Communicator& comm, const dist::Decomposition& d);

// Every rank's files, listed into its `files`, merged on rank 0 in the order each was listed
// (ManifestFile::listing): the single process's order. The other ranks' `files` are left as they
// are.
void mergeTheRanksFiles(const dist::Communicator& comm, OutputSink& files);

}  // namespace snow
