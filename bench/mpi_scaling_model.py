#!/usr/bin/env python3
"""Predicted efficiency of a 10^6-trial study on 100 and 1,000 MPI ranks (issue 17).

usage: mpi_scaling_model.py [MPI_BENCH_JSON] [--trials N] [--ranks 100,1000]
                            [--latency-us L] [--bandwidth-gbs B] [--cv C]

The inputs are measured by bench/mpi_bench (run under mpirun; its JSON with
--benchmark_out): the time of one trial (BM_Sweep's trial_ms), the cost of one case to the
machinery (BM_CaseOverhead's ns_per_case: dealing it, its result message, rank 0 storing it,
the final broadcast, all on this machine's shared memory) and a result's size (result_bytes).
What one machine cannot measure is the network: the latency and bandwidth default to a
commodity cluster's InfiniBand (2 us, 10 GB/s); pass Ethernet's (30 us, 1 GB/s) to see it.

The model is a simulation of what lib/wobble/mpi/mpi_distributor.cc does:
- rank 0 deals chunks of left / (3 ranks) trials (at least 1) in the order requests reach it,
  one request at a time: a request costs it ns_per_case for each result it carries plus one
  message each way (latency + size / bandwidth);
- every rank, rank 0 included, computes its chunk one trial after the other; trials cost
  trial_ms times a log-normal factor of coefficient of variation C (default 0.3: synthesis
  trials that stop early or run long), so chunks end at different times;
- rank 0's dealing takes time from its own computing (one core does both), or, the other
  row of each rank count, rank 0 only deals (what MpiDistributor does from kDealerOnlyRanks);
- at the end every result goes to every rank: a pipelined broadcast of trials x (result + 9)
  bytes, 2 x size / bandwidth + log2(ranks) x latency.
Efficiency = trials x trial time / (ranks x wall time).
"""
import argparse
import heapq
import json
import math
import random


def measured(path):
    data = json.load(open(path))
    values = {}
    for b in data["benchmarks"]:
        if b["name"].startswith("BM_Sweep"):
            values["trial_ms"] = b["trial_ms"]
            values["efficiency_2"] = b.get("efficiency")
            values["ranks_measured"] = b.get("ranks")
        if b["name"].startswith("BM_CaseOverhead"):
            values["ns_per_case"] = b["ns_per_case"]
            values["result_bytes"] = b["result_bytes"]
    return values


def simulate(ranks, trials, trial_s, case_s, result_bytes, latency_s, bandwidth, cv, dealer_computes, seed=1):
    rng = random.Random(seed)
    sigma = math.sqrt(math.log(1 + cv * cv))
    mu = -0.5 * sigma * sigma  # mean factor 1

    def chunk_time(count):
        # sum of `count` log-normal trial times: exact for small chunks, normal approximation above
        if count <= 32:
            return sum(trial_s * math.exp(rng.gauss(mu, sigma)) for _ in range(count))
        mean = count * trial_s
        sd = math.sqrt(count) * trial_s * cv
        return max(0.0, rng.gauss(mean, sd))

    left = trials
    master_free = 0.0      # when rank 0's dealer is next free
    master_busy = 0.0      # total dealing time (taken from rank 0's computing)
    events = [(0.0, r, 0) for r in range(1, ranks)]  # (time a request is sent, rank, results carried)
    heapq.heapify(events)
    finish = [0.0] * ranks
    # rank 0 computes between its dealing: its chunks are taken like any other rank's
    own_time = 0.0
    while events or left > 0:
        # the next request to reach rank 0: a worker's, or rank 0's own when it is free first
        if events and (events[0][0] + latency_s <= own_time or left == 0 or not dealer_computes):
            sent, rank, carried = heapq.heappop(events)
            arrival = sent + latency_s + carried * (result_bytes + 17) / bandwidth
            start = max(arrival, master_free)
            service = carried * case_s + 2e-6
            master_free = start + service
            master_busy += service
            count = min(left, max(1, left // (3 * ranks)))
            left -= count
            if count == 0:
                finish[rank] = master_free
                continue
            begin = master_free + latency_s
            heapq.heappush(events, (begin + chunk_time(count), rank, count))
        else:
            count = min(left, max(1, left // (3 * ranks)))
            left -= count
            own_time += chunk_time(count) + count * case_s
    finish[0] = own_time + master_busy if dealer_computes else master_free
    size = trials * (result_bytes + 9)
    broadcast = 2 * size / bandwidth + math.ceil(math.log2(max(ranks, 2))) * latency_s
    wall = max(finish) + broadcast
    return trials * trial_s / (ranks * wall), wall, master_busy, broadcast


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("json", nargs="?", help="mpi_bench's --benchmark_out JSON (under mpirun)")
    p.add_argument("--trials", type=int, default=1_000_000)
    p.add_argument("--ranks", default="2,100,1000")
    p.add_argument("--latency-us", type=float, default=2.0)
    p.add_argument("--bandwidth-gbs", type=float, default=10.0)
    p.add_argument("--cv", type=float, default=0.3)
    p.add_argument("--trial-ms", type=float, help="instead of the JSON's")
    p.add_argument("--ns-per-case", type=float, help="instead of the JSON's")
    a = p.parse_args()
    m = measured(a.json) if a.json else {}
    trial_ms = a.trial_ms or m.get("trial_ms")
    ns_per_case = a.ns_per_case or m.get("ns_per_case")
    result_bytes = m.get("result_bytes", 41.0)
    if trial_ms is None or ns_per_case is None:
        p.error("give mpi_bench's JSON or --trial-ms and --ns-per-case")
    print(f"inputs: trial {trial_ms:.3f} ms, {ns_per_case:.0f} ns per case to the machinery, result "
          f"{result_bytes:.0f} bytes; network {a.latency_us} us, {a.bandwidth_gbs} GB/s; trial-time CV {a.cv}")
    if m.get("efficiency_2") is not None:
        print(f"measured on this machine: efficiency {m['efficiency_2']:.3f} on {m['ranks_measured']:.0f} ranks "
              f"(10,000 trials)")
    print(f"{'ranks':>6} {'rank 0':>9} {'efficiency':>10} {'wall s':>9} {'rank 0 dealing s':>17} {'broadcast s':>12}")
    for n in [int(x) for x in a.ranks.split(",")]:
        for computes in (True, False):
            if n < 2 and not computes:
                continue
            e, wall, busy, bcast = simulate(n, a.trials, trial_ms * 1e-3, ns_per_case * 1e-9, result_bytes,
                                            a.latency_us * 1e-6, a.bandwidth_gbs * 1e9, a.cv, computes)
            role = "computes" if computes else "deals"
            print(f"{n:>6} {role:>9} {e:>10.3f} {wall:>9.2f} {busy:>17.3f} {bcast:>12.3f}")


if __name__ == "__main__":
    main()
