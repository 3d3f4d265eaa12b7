// The processes of a build: MPI's ranks when the tool is launched by mpirun (and built with MPI,
// RTOG_MPI), else this process alone. The only place the tool speaks MPI.
#pragma once

#include <string>
#include <vector>

namespace rtog::cli {

class Ranks {
 public:
  /// Joins the job if a launcher started this process (MPI initialised here, finalised by the
  /// destructor); else one rank of one.
  Ranks();
  ~Ranks();
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Every rank's text, in rank order, at rank 0; an empty list elsewhere.
  std::vector<std::string> gather(const std::string& mine) const;
  void barrier() const;
  /// True on every rank if `ok` is true on every rank.
  bool all(bool ok) const;

 private:
  int rank_ = 0, size_ = 1;
  bool mpi_ = false;
};

}  // namespace rtog::cli
