#!/usr/bin/env python3
"""Times two edmp-host builds (OLD, NEW) and RRT-Connect alternately on 40 suite problems (every
10th of each family): how much of a timing difference is the machine and how much the code.
Usage: OLD=/path/to/old/edmp-host python3 benchmarks/ab_timing.py (run from the repository root)."""
import json, subprocess, statistics, sys
import os
OLD=os.environ.get("OLD", "./target-old/release/edmp-host"); NEW=os.environ.get("NEW", "./target/release/edmp-host")
probs=[f"benchmarks/problems/{f}/{i:03}.json" for f in ["tabletop","cubby","merged_cubby","dresser"] for i in range(0,100,10)]
t={"old":[], "new":[], "new_first":[], "rrt":[]}
for p in probs:
    for name,b in [("old",OLD),("new",NEW)]:
        d=json.loads(subprocess.run([b,"plan",p],capture_output=True,text=True).stdout)
        t[name].append(d["timing_ms"]["total"])
        if name=="new": t["new_first"].append(d["timing_ms"]["total"]-d["timing_ms"].get("global",0))
    d=json.loads(subprocess.run([NEW,"rrt",p,"--seed","0"],capture_output=True,text=True).stdout)
    t["rrt"].append(d["timing_ms"]["total"])
for k,v in t.items(): print(k, "median %.1f ms  p95 %.1f"%(statistics.median(v), sorted(v)[int(0.95*(len(v)-1))]))
print("ratio new/old per problem, median: %.3f"%statistics.median([n/o for n,o in zip(t["new_first"],t["old"])]))
