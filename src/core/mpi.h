// The one place RayPC talks to MPI (docs/scaling.md). Everything else (preprocess, stats, render,
// the CLI) calls these functions; no MPI call and no <mpi.h> outside core/mpi.cpp.
//
// One `raypc` binary: started by an MPI launcher (mpirun, mpiexec, srun) it is one rank of many;
// started alone it is rank 0 of 1 and never initialises MPI (an Open MPI singleton init costs
// ~0.7 s, so a plain `raypc info` would pay it for nothing). Every collective below is then a
// no-op that returns its input, so callers are written once for both cases.
//
// Errors: work that may fail on some ranks runs inside together(); at its end every rank learns
// whether any rank threw, and then every rank throws the same AgreedError (the message of the
// lowest failing rank). main() prints an AgreedError once, on rank 0; any other error on a rank
// of many is printed by that rank and ends the job with MPI_Abort (reportFailure), so a rank
// that fails outside together() cannot leave the others waiting in a collective.
//
// Thread safety: MPI is initialised with MPI_THREAD_FUNNELED; call these functions from the
// main thread only (oneTBB workers never call them).
#pragma once

#include "core/error.h"

#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace raypc::mpi {

// Scoped MPI for main(): MPI_Init_thread if a launcher started the process (launchedByMpi), and
// MPI_Finalize at the end. Throws raypc::Error if MPI is needed but cannot start.
class Environment {
public:
    Environment(int& argc, char**& argv);
    ~Environment();
    Environment(const Environment&) = delete;
    Environment& operator=(const Environment&) = delete;
};

// True when the environment says an MPI launcher started this process (Open MPI / PMIx:
// PMIX_RANK or OMPI_COMM_WORLD_RANK; MPICH/Hydra and Slurm's PMI: PMI_RANK).
bool launchedByMpi();

int rank();  // 0 without MPI
int size();  // 1 without MPI
inline bool isRoot() { return rank() == 0; }
inline bool distributed() { return size() > 1; }

// The error every rank throws when one rank's work inside together() failed; the message is that
// rank's (the lowest failing rank's when several failed).
class AgreedError : public Error {
public:
    explicit AgreedError(const std::string& message) : Error(message) {}
};

// Runs `work` on this rank, then agrees with every rank: if any rank's work threw (raypc::Error or
// any std::exception), every rank throws AgreedError with one message. Collective.
void together(const std::function<void()>& work);

// For main's catch: prints the message once (rank 0 for an AgreedError, the failing rank otherwise,
// naming it) and returns the exit status; on a rank of many with an error the others did not agree
// on, it ends the whole job with MPI_Abort instead of returning.
int reportFailure(const std::exception& error);

// Collectives: every rank calls them in the same order. Without MPI they return the input.
void barrier();
// Every rank's string, in rank order, on every rank.
std::vector<std::string> allgather(const std::string& mine);
// Every rank's string, in rank order, on rank 0 (empty elsewhere).
std::vector<std::string> gatherToRoot(const std::string& mine);
// Rank 0's value on every rank.
std::string broadcast(const std::string& value);
// Element-wise sums over ranks, on every rank.
void sum(std::span<int64_t> values);
int64_t sum(int64_t value);
// Every rank's floats appended in rank order, on rank 0 (empty elsewhere).
std::vector<float> gatherToRoot(std::span<const float> mine);

// Point-to-point messages (the distributed server, server/rank_pool.h): tagged byte strings, from
// the main thread like everything here. Tags are the caller's (0..32767).
constexpr int kAnySource = -1;
constexpr int kAnyTag = -1;
struct Message {
    int source = 0;
    int tag = 0;
    std::string bytes;
};
// Sends `bytes` to rank `destination` (returns when the buffer may be reused: at once for small
// messages, when the receiver has started to take a large one).
void send(int destination, int tag, const std::string& bytes);
// A message from `source` with `tag` (kAnySource, kAnyTag: any) if one has arrived, received;
// nullopt at once otherwise. Polling with a short sleep in between keeps a waiting rank from
// spinning a core (MPI's blocking receive busy-waits on shared memory). Without MPI: nullopt.
std::optional<Message> tryReceive(int source, int tag);

// A send that returns at once (MPI_Isend): for a rank that answers when its work is done rather than
// when asked, so that it never blocks in a send while the receiver blocks sending to it. The
// message goes while done() is polled; the destructor waits for it (the receiver must take it).
class PendingSend {
public:
    PendingSend(int destination, int tag, std::string bytes);
    ~PendingSend();
    PendingSend(const PendingSend&) = delete;
    PendingSend& operator=(const PendingSend&) = delete;
    bool done();

private:
    struct Request;
    std::string m_bytes;
    std::unique_ptr<Request> m_request;
};

// The contiguous block of [0, count) that this rank takes in a static split (balanced to one item),
// and that rank `rank` of `ranks` takes (without MPI too: a server's jobs name their rank).
struct Block {
    int64_t begin = 0, end = 0;
};
Block blockOf(int64_t count);
Block blockOf(int64_t count, int rank, int ranks);

// Hands the items 0..count-1 out one at a time to whichever rank asks first (a counter on rank 0
// read with MPI_Fetch_and_op), so a rank that finishes early takes more. Calls `work(item)` for
// each item this rank takes and `handedOut(n)` on rank 0 with the number of items handed out to
// all ranks so far (for progress). A rank whose work throws stops every rank from taking further
// items; then every rank throws the AgreedError (as together()). Collective.
void forEachDynamic(int64_t count, const std::function<void(int64_t item)>& work,
                    const std::function<void(int64_t handedOut)>& handedOut = {});

// Test hook (docs/scaling.md): with RAYPC_TEST_DIE_RANK=R and RAYPC_TEST_DIE_AT=PHASE set, rank R
// exits at once with status 3, without MPI_Finalize, when it reaches dieHook(PHASE): a rank that
// dies mid-run. Does nothing otherwise.
void dieHook(const char* phase);

}  // namespace raypc::mpi
