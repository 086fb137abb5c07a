// The MPI runner of core/distribute.h (Open MPI; built when CMake finds MPI): `mpirun -np N
// wobble ...` runs the same command on every rank, and every DistributedMap is dealt out by
// rank 0 in chunks as ranks ask for work (guided self-scheduling, so cases of very different
// cost keep every rank busy), run on each rank's threads, and gathered back to every rank.
//
// Below 48 ranks rank 0 computes too: one thread of it answers the other ranks while the rest
// run items; from 48 on it only deals (the crossover of bench/mpi_scaling_model.py).
// Nothing waits in a spinning MPI call: waits poll and sleep, so ranks oversubscribed on a
// few cores (`--oversubscribe`) leave the CPU to the ranks that compute.
#pragma once

#include <memory>

#include "wobble/core/distribute.h"

namespace wobble::mpi {

// Whether this process was started by mpirun (Open MPI's or a PMI launcher's environment).
bool LaunchedByMpirun();

// MPI_Init_thread on construction (threads: funneled, only the calling thread talks MPI),
// MPI_Finalize on destruction; installs itself as the CurrentDistributor meanwhile.
class MpiDistributor final : public Distributor {
 public:
  MpiDistributor(int* argc, char*** argv);
  ~MpiDistributor() override;
  MpiDistributor(const MpiDistributor&) = delete;
  MpiDistributor& operator=(const MpiDistributor&) = delete;

  std::vector<Bytes> Map(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item) override;
  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }
  // Ends every rank at once (MPI_Abort): for a failure on one rank that the others cannot see.
  [[noreturn]] void Abort(int code);

 private:
  std::vector<Bytes> Deal(size_t n, const MapOptions& options, const std::function<Bytes(size_t)>& item);
  void Work(const MapOptions& options, const std::function<Bytes(size_t)>& item);
  int rank_ = 0, ranks_ = 1;
  int threads_per_rank_ = 1;  // what threads = 0 means: this node's cores shared by its ranks
};

}  // namespace wobble::mpi
