#include "communicator.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "launch.h"

#ifdef SNOWBAKE_MPI
#include <mpi.h>
#endif

namespace snow::dist {

#ifdef SNOWBAKE_MPI

namespace {
bool sessionOpen = false;
NodeShare thisNode;
void check(int status, const char* what) {
  if (status != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}
// Blocks above 1 GiB travel in pieces: MPI counts are ints.
constexpr size_t kPiece = size_t(1) << 30;
}  // namespace

MpiSession::MpiSession() {
  if (launchedRanks() <= 1) return;  // alone: no MPI, as a build without it
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) {
    int provided = 0;
    check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    if (provided < MPI_THREAD_FUNNELED) throw std::runtime_error("MPI: this MPI does not allow threads beside the main one (TBB's)");
  }
  sessionOpen = true;
  // The ranks sharing this machine's memory, and whether world rank 0 is among them.
  MPI_Comm node;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node), "MPI_Comm_split_type");
  int worldRank = 0, zeroHere = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &worldRank);
  const int mine = worldRank == 0 ? 1 : 0;
  check(MPI_Allreduce(&mine, &zeroHere, 1, MPI_INT, MPI_MAX, node), "MPI_Allreduce");
  MPI_Comm_size(node, &thisNode.ranks);
  thisNode.holdsRankZero = zeroHere != 0;
  MPI_Comm_free(&node);
}

MpiSession::~MpiSession() {
  if (!sessionOpen) return;
  int done = 0;
  MPI_Finalized(&done);
  if (!done) MPI_Finalize();
  sessionOpen = false;
  thisNode = NodeShare{};
}

NodeShare Communicator::node() { return sessionOpen ? thisNode : NodeShare{}; }

bool Communicator::hasMpi() { return true; }

Communicator Communicator::world() {
  if (!sessionOpen) return Communicator(0, 1);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return Communicator(rank, size);
}

void Communicator::exchange(const std::vector<Send>& sends, const std::vector<Receive>& receives) const {
  if (size_ == 1) {
    if (!sends.empty() || !receives.empty()) throw std::logic_error("Communicator::exchange: one rank has no peers");
    return;
  }
  // Empty blocks are not posted (both sides compute the same sizes from the same plan).
  std::vector<MPI_Request> requests;
  for (const Receive& r : receives)
    for (size_t at = 0; at < r.bytes; at += kPiece) {
      requests.emplace_back();
      check(MPI_Irecv(static_cast<char*>(r.data) + at, static_cast<int>(std::min(kPiece, r.bytes - at)), MPI_BYTE, r.peer, 0,
                      MPI_COMM_WORLD, &requests.back()),
            "MPI_Irecv");
    }
  for (const Send& s : sends)
    for (size_t at = 0; at < s.bytes; at += kPiece) {
      requests.emplace_back();
      check(MPI_Isend(static_cast<const char*>(s.data) + at, static_cast<int>(std::min(kPiece, s.bytes - at)), MPI_BYTE, s.peer, 0,
                      MPI_COMM_WORLD, &requests.back()),
            "MPI_Isend");
    }
  check(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
}

std::vector<double> Communicator::allGather(const std::vector<double>& mine) const {
  if (size_ == 1) return mine;
  std::vector<int> counts(static_cast<size_t>(size_)), offsets(static_cast<size_t>(size_));
  const int count = static_cast<int>(mine.size());
  check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  int total = 0;
  for (int r = 0; r < size_; ++r) offsets[r] = total, total += counts[r];
  std::vector<double> all(static_cast<size_t>(total));
  check(MPI_Allgatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD),
        "MPI_Allgatherv");
  return all;
}

float Communicator::maxOverRanks(float value) const {
  if (size_ == 1) return value;
  float out = value;
  check(MPI_Allreduce(&value, &out, 1, MPI_FLOAT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
}

void Communicator::barrier() const {
  if (size_ > 1) check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
}

void Communicator::abortAll(int status) const {
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

#else  // one process alone

MpiSession::MpiSession() = default;
MpiSession::~MpiSession() = default;
bool Communicator::hasMpi() { return false; }
Communicator Communicator::world() { return Communicator(0, 1); }
NodeShare Communicator::node() { return NodeShare{}; }
void Communicator::exchange(const std::vector<Send>& sends, const std::vector<Receive>& receives) const {
  if (!sends.empty() || !receives.empty()) throw std::logic_error("Communicator::exchange: one rank has no peers");
}
std::vector<double> Communicator::allGather(const std::vector<double>& mine) const { return mine; }
float Communicator::maxOverRanks(float value) const { return value; }
void Communicator::barrier() const {}
void Communicator::abortAll(int status) const { std::exit(status); }

#endif

}  // namespace snow::dist
