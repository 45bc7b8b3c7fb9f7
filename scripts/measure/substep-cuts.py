"""Summarises the stderr of the instrumented landing pile (scripts/measure/substep-cuts.sh):
what bounds each sub-step the conservative-advancement bound cuts short, steps FROM to the end."""
import statistics
import sys

FROM = 60
COLLIDE_THRESHOLD = 1e-3 + 2 * 9.81 / 120  # v_rest + 2|g|h at h = 1/120 s


def main(path):
    step, cuts, comps = None, [], []
    for line in open(path):
        words = line.split()
        if not words:
            continue
        if words[0] == "STEP":
            step = int(words[1])
        elif step is not None and step >= FROM and words[0] == "CUT":
            fields = dict(w.split("=") for w in words[2:])
            cuts.append((words[1], fields))
        elif step is not None and step >= FROM and words[0] == "COMP":
            fields = dict(w.split("=") for w in words[1:])
            fields["step"] = step
            comps.append(fields)
    pairs = [f for kind, f in cuts if kind == "pair"]
    print(f"cuts {len(cuts)}: bound by a pair {len(pairs)}, by a body margin {len(cuts) - len(pairs)}")
    fast = sum(float(f["normal"]) > COLLIDE_THRESHOLD for f in pairs)
    slow = sum(0 < float(f["normal"]) <= COLLIDE_THRESHOLD for f in pairs)
    print(f"closing along the best axis: faster than {COLLIDE_THRESHOLD:.3f} m/s {fast}, slower {slow}, "
          f"apart {len(pairs) - fast - slow}")
    def deciles(values):
        values = sorted(values)
        return values[len(values) // 10], values[(9 * len(values)) // 10]

    speed = deciles(float(f["normal"]) for f in pairs if float(f["normal"]) > COLLIDE_THRESHOLD)
    gaps = deciles(float(f["alltrue"]) for f in pairs)
    print(f"closing speed of the fast ones, 10th-90th percentile: {speed[0]:.2f}-{speed[1]:.2f} m/s; "
          f"nearest true leaf gap (distance less the approach): {1e3 * gaps[0]:.1f}-{1e3 * gaps[1]:.1f} mm")
    loose = sum(float(f["alltrue"]) > 1.5 * float(f["gap"]) for f in pairs)
    print(f"cuts whose nearest true leaf gap exceeds 1.5x the reported one: {loose}")
    share = [int(c["pairs_in"]) / int(c["pairs_all"]) for c in comps]
    big = [x for x in share if x >= 0.25]
    mean_big = statistics.mean(big) if big else float("nan")
    print(f"cuts in a component with >= 1/4 of the pairs {len(big)} (mean share {mean_big:.2f}), "
          f"in smaller ones {len(share) - len(big)}; median bodies in the component "
          f"{statistics.median(int(c['bodies_in']) for c in comps)}")
    by_step = {}
    for c, x in zip(comps, share):
        by_step.setdefault(c["step"], []).append(x)
    steps = range(FROM, max(by_step) + 1) if by_step else []
    global_work, local_work = 0, 0.0
    for s in steps:
        xs = by_step.get(s, [])
        global_work += 1 + len(xs)
        large = [x for x in xs if x >= 0.25]
        small = [x for x in xs if x < 0.25]
        # The large component's share of the pairs; in a step where it was not cut, its mean
        # share over the cuts that fell in it.
        share_large = max(large) if large else (statistics.mean(big) if big else 1.0)
        local_work += share_large * (1 + len(large)) + sum(small) + (1 - share_large)
    print(f"pair-weighted sub-steps: global {global_work}, per island (estimate) {local_work:.0f}")


main(sys.argv[1])
