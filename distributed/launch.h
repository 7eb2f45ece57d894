// How many processes a launcher (mpirun, srun) started, read from its environment without
// initialising MPI: header only, so the program can ask without linking MPI.
#pragma once
#include <cstdlib>
#include <cstring>
#include <initializer_list>

namespace snow::dist {

namespace detail {
// The first of `names` set to a whole number in [lo, hi], else `fallback`.
inline int launcherNumber(std::initializer_list<const char*> names, long lo, long hi, int fallback) {
  for (const char* name : names) {
    if (!*name) continue;
    const char* v = std::getenv(name);
    if (!v || !*v) continue;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    if (*end == '\0' && n >= lo && n <= hi) return static_cast<int>(n);
  }
  return fallback;
}
}  // namespace detail

// 1 when the program was started alone (or by a launcher with one process).
inline int launchedRanks() {
  // OpenMPI's mpirun, then PMI (MPICH, srun --mpi=pmi2), then an srun step's tasks (srun sets a
  // numeric SLURM_STEP_ID; a batch script, whose SLURM_NTASKS may count cores for one process,
  // runs in no such step, or in Slurm's batch or extern step, 4294967294 and 4294967295).
  const char* step = std::getenv("SLURM_STEP_ID");
  const bool srunStep = step && *step && std::strspn(step, "0123456789") == std::strlen(step) && std::strlen(step) < 10;
  return detail::launcherNumber({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", srunStep ? "SLURM_STEP_NUM_TASKS" : ""}, 1, 1L << 20, 1);
}

// This process's rank among them (0 alone), from the same launchers' environment.
inline int launchedRank() {
  if (launchedRanks() <= 1) return 0;
  return detail::launcherNumber({"OMPI_COMM_WORLD_RANK", "PMI_RANK", "SLURM_PROCID"}, 0, (1L << 20) - 1, 0);
}

}  // namespace snow::dist
