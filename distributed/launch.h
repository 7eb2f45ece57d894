// How many processes a launcher (mpirun, srun) started, read from its environment without
// initialising MPI: header only, so the program can ask without linking MPI.
#pragma once
#include <cstdlib>
#include <cstring>

namespace snow::dist {

// 1 when the program was started alone (or by a launcher with one process).
inline int launchedRanks() {
  // OpenMPI's mpirun, then PMI (MPICH, srun --mpi=pmi2), then an srun step's tasks (srun sets a
  // numeric SLURM_STEP_ID; a batch script, whose SLURM_NTASKS may count cores for one process,
  // runs in no such step, or in Slurm's batch or extern step, 4294967294 and 4294967295).
  const char* step = std::getenv("SLURM_STEP_ID");
  const bool srunStep = step && *step && std::strspn(step, "0123456789") == std::strlen(step) && std::strlen(step) < 10;
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", srunStep ? "SLURM_STEP_NUM_TASKS" : ""}) {
    if (!*name) continue;
    const char* v = std::getenv(name);
    if (!v || !*v) continue;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    if (*end == '\0' && n >= 1 && n <= (1L << 20)) return static_cast<int>(n);
  }
  return 1;
}

// This process's rank among them (0 alone), from the same launchers' environment.
inline int launchedRank() {
  if (launchedRanks() <= 1) return 0;
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "SLURM_PROCID"}) {
    const char* v = std::getenv(name);
    if (!v || !*v) continue;
    char* end = nullptr;
    const long n = std::strtol(v, &end, 10);
    if (*end == '\0' && n >= 0 && n < (1L << 20)) return static_cast<int>(n);
  }
  return 0;
}

}  // namespace snow::dist
