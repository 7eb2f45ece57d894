// The processes of a distributed bake (docs/distributed.md): MPI's world when the build has MPI
// (SNOWBAKE_MPI) and a launcher (mpirun, srun) started the program, else one process alone. Only
// what the decomposition needs: point-to-point blocks, a gather of doubles in rank order, a
// maximum and a barrier.
#pragma once
#include <cstddef>
#include <vector>

namespace snow::dist {

// Initialises MPI for the program's life where the build has it and a launcher started more than
// one process (threads: funnelled; only the main thread calls MPI, TBB's workers never do), and
// finalises it at the end of scope.
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
};

// The ranks of the launch that share this rank's machine (its memory), found once as the session
// opens (every rank opens it together, before any can fail): how many, and whether rank 0 is one.
struct NodeShare {
  int ranks = 1;
  bool holdsRankZero = true;
};

class Communicator {
 public:
  // Every process of the launch; one process alone without MPI or before an MpiSession.
  static Communicator world();
  // This rank's machine's share of the launch; one process alone: itself.
  static NodeShare node();
  // Whether this build has MPI (SNOWBAKE_MPI).
  static bool hasMpi();
  int rank() const { return rank_; }
  int size() const { return size_; }

  struct Send {
    int peer;
    const void* data;
    size_t bytes;
  };
  struct Receive {
    int peer;
    void* data;
    size_t bytes;
  };
  // Posts every receive and send at once, then waits for all: a halo exchange with any number of
  // neighbours without deadlock. Blocks between one pair of ranks travel in the order posted.
  void exchange(const std::vector<Send>& sends, const std::vector<Receive>& receives) const;
  // Every rank's values concatenated in rank order, on every rank.
  std::vector<double> allGather(const std::vector<double>& mine) const;
  // The largest of the ranks' values, on every rank.
  float maxOverRanks(float value) const;
  void barrier() const;
  // Ends every rank of the launch at once with `status` (MPI_Abort): a failure while the others
  // wait in an exchange. One process alone: std::exit.
  [[noreturn]] void abortAll(int status) const;

 private:
  Communicator(int rank, int size) : rank_(rank), size_(size) {}
  int rank_ = 0, size_ = 1;
};

}  // namespace snow::dist
