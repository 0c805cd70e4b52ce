"""What else ran on the machine while a study measured: load averages, the whole machine's busy and stolen CPU
seconds, this process's and its worker's own, and what two snapshots say between them (wall seconds, the other
processes' CPU in cores). Linux /proc; standard library only."""

import os
import resource
import time

TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100



def load_average():
    return [round(x, 2) for x in os.getloadavg()]



def machine_cpu_seconds():
    """(busy, steal) CPU seconds of the whole machine since boot from /proc/stat, or None."""
    try:
        with open("/proc/stat") as f:
            fields = [int(x) for x in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    user, nice, system, idle, iowait, irq, softirq = fields[:7]
    steal = fields[7] if len(fields) > 7 else 0
    return (user + nice + system + irq + softirq) / TICK, steal / TICK



def own_cpu_seconds(worker_pid):
    """CPU seconds of this process, its finished children (our mipnerf-cl runs) and the official worker."""
    own = sum(resource.getrusage(who).ru_utime + resource.getrusage(who).ru_stime
              for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    try:
        with open(f"/proc/{worker_pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        own += sum(int(x) for x in fields[11:15]) / TICK  # utime stime cutime cstime
    except (OSError, ValueError, IndexError):
        return None
    return own



def snapshot(worker):
    return {"t": time.monotonic(), "load": load_average(), "machine": machine_cpu_seconds(),
            "own": own_cpu_seconds(worker.proc.pid)}



def between(before, after):
    """What a round's snapshots say: wall seconds, load averages, the other processes' CPU (in cores)."""
    wall = after["t"] - before["t"]
    out = {"wall_s": wall, "load_before": before["load"], "load_after": after["load"],
           "other_cpu_cores": None, "steal_cores": None}
    if before["machine"] and after["machine"] and before["own"] is not None and after["own"] is not None and wall > 0:
        busy = after["machine"][0] - before["machine"][0]
        own = after["own"] - before["own"]
        out["other_cpu_cores"] = max(0.0, busy - own) / wall
        out["steal_cores"] = (after["machine"][1] - before["machine"][1]) / wall
    return out
