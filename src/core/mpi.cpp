#include "core/mpi.h"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <unistd.h>

namespace raypc::mpi {
namespace {

bool g_active = false;  // MPI_Init_thread was called by Environment
int g_rank = 0, g_size = 1;

// MPI's counts are int: a message beyond 2^31 - 1 elements must be split, which RayPC never needs
// (the largest, a 16384² image's tiles, is 1.6e9 floats at most).
int toCount(size_t n, const char* what)
{
    if (n > size_t(std::numeric_limits<int>::max()))
        fail("MPI: {} of {} elements is more than one message can carry", what, n);
    return int(n);
}

std::vector<int> displacements(const std::vector<int>& counts)
{
    std::vector<int> displs(counts.size(), 0);
    int64_t total = 0;
    for (size_t i = 0; i < counts.size(); ++i) {
        displs[i] = toCount(size_t(total), "a gathered message");
        total += counts[i];
    }
    toCount(size_t(total), "a gathered message");
    return displs;
}

}  // namespace

bool launchedByMpi()
{
    for (const char* name : {"PMIX_RANK", "OMPI_COMM_WORLD_RANK", "PMI_RANK"})
        if (std::getenv(name))
            return true;
    return false;
}

Environment::Environment(int& argc, char**& argv)
{
    if (!launchedByMpi())
        return;
    // FUNNELED: only the main thread calls MPI; oneTBB's workers render and compute.
    int provided = 0;
    if (MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        fail("MPI: MPI_Init_thread failed (started by a launcher: PMIX_RANK, OMPI_COMM_WORLD_RANK or PMI_RANK is set)");
    g_active = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
}

Environment::~Environment()
{
    if (g_active)
        MPI_Finalize();
    g_active = false;
}

int rank() { return g_rank; }
int size() { return g_size; }

void together(const std::function<void()>& work)
{
    std::exception_ptr error;
    std::string message;
    try {
        work();
    } catch (const std::exception& e) {
        error = std::current_exception();
        message = e.what();
    }
    if (!distributed()) {
        if (error)
            std::rethrow_exception(error);
        return;
    }
    // The lowest failing rank (size() when none failed) tells the others its message.
    int mine = error ? rank() : size(), lowest = size();
    MPI_Allreduce(&mine, &lowest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (lowest == size())
        return;
    uint64_t length = message.size();
    MPI_Bcast(&length, 1, MPI_UINT64_T, lowest, MPI_COMM_WORLD);
    message.resize(length);
    MPI_Bcast(message.data(), toCount(length, "an error message"), MPI_CHAR, lowest, MPI_COMM_WORLD);
    throw AgreedError(message);
}

int reportFailure(const std::exception& error)
{
    if (!distributed()) {
        std::fprintf(stderr, "raypc: error: %s\n", error.what());
        return 1;
    }
    if (dynamic_cast<const AgreedError*>(&error)) {
        if (isRoot())
            std::fprintf(stderr, "raypc: error: %s\n", error.what());
        return 1;
    }
    // The other ranks may be waiting in a collective for this one: end them all.
    std::fprintf(stderr, "raypc: error (rank %d of %d): %s\n", rank(), size(), error.what());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
}

void barrier()
{
    if (distributed())
        MPI_Barrier(MPI_COMM_WORLD);
}

std::vector<std::string> gatherToRoot(const std::string& mine)
{
    if (!distributed())
        return {mine};
    const int count = toCount(mine.size(), "a string");
    std::vector<int> counts(size_t(size()), 0);
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::vector<int> displs;
    std::string all;
    if (isRoot()) {
        displs = displacements(counts);
        all.resize(size_t(displs.back()) + size_t(counts.back()));
    }
    MPI_Gatherv(mine.data(), count, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
    std::vector<std::string> out;
    if (isRoot())
        for (size_t r = 0; r < counts.size(); ++r)
            out.push_back(all.substr(size_t(displs[r]), size_t(counts[r])));
    return out;
}

std::vector<std::string> allgather(const std::string& mine)
{
    if (!distributed())
        return {mine};
    const int count = toCount(mine.size(), "a string");
    std::vector<int> counts(size_t(size()), 0);
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    const std::vector<int> displs = displacements(counts);
    std::string all(size_t(displs.back()) + size_t(counts.back()), '\0');
    MPI_Allgatherv(mine.data(), count, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR, MPI_COMM_WORLD);
    std::vector<std::string> out;
    for (size_t r = 0; r < counts.size(); ++r)
        out.push_back(all.substr(size_t(displs[r]), size_t(counts[r])));
    return out;
}

std::string broadcast(const std::string& value)
{
    if (!distributed())
        return value;
    uint64_t length = value.size();
    MPI_Bcast(&length, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    std::string out = isRoot() ? value : std::string(length, '\0');
    MPI_Bcast(out.data(), toCount(length, "a broadcast string"), MPI_CHAR, 0, MPI_COMM_WORLD);
    return out;
}

void sum(std::span<int64_t> values)
{
    if (distributed())
        MPI_Allreduce(MPI_IN_PLACE, values.data(), toCount(values.size(), "a sum"), MPI_INT64_T, MPI_SUM,
                      MPI_COMM_WORLD);
}

int64_t sum(int64_t value)
{
    sum(std::span<int64_t>(&value, 1));
    return value;
}

std::vector<float> gatherToRoot(std::span<const float> mine)
{
    if (!distributed())
        return {mine.begin(), mine.end()};
    const int count = toCount(mine.size(), "a float array");
    std::vector<int> counts(size_t(size()), 0);
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::vector<int> displs;
    std::vector<float> all;
    if (isRoot()) {
        displs = displacements(counts);
        all.resize(size_t(displs.back()) + size_t(counts.back()));
    }
    MPI_Gatherv(mine.data(), count, MPI_FLOAT, all.data(), counts.data(), displs.data(), MPI_FLOAT, 0, MPI_COMM_WORLD);
    return all;
}

void send(int destination, int tag, const std::string& bytes)
{
    if (!distributed())
        fail("MPI: send to rank {} without MPI", destination);
    MPI_Send(bytes.data(), toCount(bytes.size(), "a message"), MPI_BYTE, destination, tag, MPI_COMM_WORLD);
}

std::optional<Message> tryReceive(int source, int tag)
{
    if (!distributed())
        return std::nullopt;
    int arrived = 0;
    MPI_Status status;
    MPI_Iprobe(source == kAnySource ? MPI_ANY_SOURCE : source, tag == kAnyTag ? MPI_ANY_TAG : tag, MPI_COMM_WORLD,
               &arrived, &status);
    if (!arrived)
        return std::nullopt;
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    Message message{status.MPI_SOURCE, status.MPI_TAG, std::string(size_t(count), '\0')};
    MPI_Recv(message.bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    return message;
}

struct PendingSend::Request {
    MPI_Request request = MPI_REQUEST_NULL;
};

PendingSend::PendingSend(int destination, int tag, std::string bytes)
    : m_bytes(std::move(bytes)), m_request(std::make_unique<Request>())
{
    if (!distributed())
        fail("MPI: send to rank {} without MPI", destination);
    MPI_Isend(m_bytes.data(), toCount(m_bytes.size(), "a message"), MPI_BYTE, destination, tag, MPI_COMM_WORLD,
              &m_request->request);
}

PendingSend::~PendingSend()
{
    if (m_request->request != MPI_REQUEST_NULL)
        MPI_Wait(&m_request->request, MPI_STATUS_IGNORE);
}

bool PendingSend::done()
{
    if (m_request->request == MPI_REQUEST_NULL)
        return true;
    int finished = 0;
    MPI_Test(&m_request->request, &finished, MPI_STATUS_IGNORE);
    return finished != 0;
}

Block blockOf(int64_t count)
{
    return blockOf(count, rank(), size());
}

Block blockOf(int64_t count, int rank, int ranks)
{
    const int64_t n = ranks, r = rank;
    const int64_t base = count / n, extra = count % n;
    const int64_t begin = r * base + std::min(r, extra);
    return {begin, begin + base + (r < extra ? 1 : 0)};
}

void forEachDynamic(int64_t count, const std::function<void(int64_t)>& work,
                    const std::function<void(int64_t)>& handedOut)
{
    if (!distributed()) {
        together([&] {
            for (int64_t i = 0; i < count; ++i) {
                work(i);
                if (handedOut)
                    handedOut(i + 1);
            }
        });
        return;
    }
    // The next item to hand out lives on rank 0; every rank (rank 0 too) takes one with an atomic
    // fetch-and-add, passive target: nobody waits for rank 0 to answer.
    int64_t* next = nullptr;
    MPI_Win window;
    MPI_Win_allocate(isRoot() ? MPI_Aint(sizeof(int64_t)) : 0, sizeof(int64_t), MPI_INFO_NULL, MPI_COMM_WORLD, &next,
                     &window);
    if (isRoot()) {
        MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, window);
        *next = 0;
        MPI_Win_unlock(0, window);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    MPI_Win_lock_all(0, window);
    auto fetchAdd = [&](int64_t add) {
        int64_t got = 0;
        MPI_Fetch_and_op(&add, &got, MPI_INT64_T, 0, 0, MPI_SUM, window);
        MPI_Win_flush(0, window);
        return got;
    };
    std::exception_ptr error;
    try {
        for (int64_t item = fetchAdd(1); item < count; item = fetchAdd(1)) {
            if (handedOut && isRoot())
                handedOut(std::min(item + 1, count));
            work(item);
        }
    } catch (...) {
        error = std::current_exception();
        // Push the counter past the end: the others finish the item they hold and take no more.
        fetchAdd(count);
    }
    MPI_Win_unlock_all(window);
    MPI_Win_free(&window);
    if (handedOut && isRoot() && !error)
        handedOut(count);
    together([&] {
        if (error)
            std::rethrow_exception(error);
    });
}

void dieHook(const char* phase)
{
    const char* dieRank = std::getenv("RAYPC_TEST_DIE_RANK");
    const char* dieAt = std::getenv("RAYPC_TEST_DIE_AT");
    if (!dieRank || !dieAt || std::strcmp(dieAt, phase) != 0 || std::atoi(dieRank) != rank())
        return;
    std::fprintf(stderr, "raypc: test hook RAYPC_TEST_DIE_AT=%s: rank %d exits\n", phase, rank());
    std::fflush(stderr);
    _exit(3);
}

}  // namespace raypc::mpi
