# SPDX-License-Identifier: Apache-2.0
"""CPU load of the estimator from the executed-instruction counts of tools/firmware-budget.

The counts are exact (QEMU, TCG plugin); cycles are not. Each core gets a CPI range (cycles per
executed instruction) stated with its reason, and the load is

    ISR:   instructions x CPI x f_s / f_clk          (per second of motor time)
    solve: instructions x CPI / (window_s x f_clk)   (once per window, in the background)

The 200 MHz DSP is not measured (no C28x compiler here): its row is an estimate from the
Cortex-M counts, and says so.
"""

# core: clock [Hz], which counts it uses, CPI ranges (ISR, solve), and why.
CORES = [
    dict(name="Cortex-M4F 168 MHz (STM32F4, ART accelerator)", clk=168e6, counts="m4",
         cpi_isr=(1.1, 1.6), cpi_solve=(1.2, 1.8), measured=True,
         why="most ALU and FPU instructions 1 cycle, VLDR/LDR 2 (pipelined runs of loads n+1), "
             "branches 1-3 (pipeline refill), VDIV/VSQRT 14; flash at 5 wait states behind the ART "
             "accelerator (prefetch + 1 KB instruction cache): straight-line ISR code mostly hits, "
             "a taken branch to a missed line costs up to 5 more; the solve's soft-double (libgcc) "
             "routines are call- and branch-heavy"),
    dict(name="Cortex-M7 480 MHz (STM32H7, caches on)", clk=480e6, counts="m7",
         cpi_isr=(0.6, 1.2), cpi_solve=(0.7, 1.3), measured=True,
         why="dual issue (two ALU, or ALU + load, per cycle), double-precision FPU; with the "
             "code in ITCM or the I-cache hot and the data in DTCM about 0.6-0.8; the upper end "
             "for the first samples after the background ran (I/D-cache lines evicted, AXI flash "
             "and SRAM wait states)"),
    dict(name="200 MHz DSP (TI C28x + FPU32, e.g. F2837x)", clk=200e6, counts="m4",
         cpi_isr=(1.0, 2.0), cpi_solve=(1.5, 3.0), measured=False,
         why="NOT MEASURED (no C28x compiler here). Estimate: the Cortex-M4F's instruction "
             "counts taken as C28x instructions (both 32-bit load/store machines with a "
             "single-precision FPU), times 1-2 cycles for the ISR (FPU32 results have a "
             "1-cycle delay slot the compiler fills or pads) and 1.5-3 for the solve (float64 in "
             "software in TI's run-time library, as libgcc's on the M4F); parts with FPU64 "
             "(F2838x, F28P65x) would be nearer the Cortex-M7's solve count"),
]


def read_counts(path):
    """The 'NAME TARGET VALUE' lines of tools/firmware-budget's stdout: {(name, target): value}."""
    c = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            p = line.split()
            if len(p) == 3 and not line.startswith("#"):
                try:
                    c[(p[0], p[1])] = float(p[2])
                except ValueError:
                    pass
    return c


def table(counts, rates=(10e3, 20e3), window_s=1.0):
    """Rows (core, rate, ISR mean %, ISR max %, solve %) as (lo, hi) ranges of % CPU."""
    rows = []
    for core in CORES:
        t = core["counts"]
        isr_mean = counts[("isr_instructions_mean", t)]
        isr_max = counts[("isr_instructions_max", t)]
        solve = counts[("solve_instructions_max", t)]
        for fs in rates:
            lo, hi = core["cpi_isr"]
            slo, shi = core["cpi_solve"]
            rows.append(dict(
                core=core["name"], fs_hz=fs, measured=core["measured"],
                isr_instr=isr_mean, isr_max_instr=isr_max, solve_instr=solve,
                isr_pct=(100 * isr_mean * lo * fs / core["clk"], 100 * isr_mean * hi * fs / core["clk"]),
                isr_max_us=(1e6 * isr_max * lo / core["clk"], 1e6 * isr_max * hi / core["clk"]),
                solve_pct=(100 * solve * slo / (window_s * core["clk"]),
                           100 * solve * shi / (window_s * core["clk"])),
                solve_ms=(1e3 * solve * slo / core["clk"], 1e3 * solve * shi / core["clk"]),
            ))
    return rows


def markdown(counts, source, window_s=1.0):
    rows = table(counts, window_s=window_s)
    out = ["| core | f_s | ISR instructions (mean / max) | ISR %% CPU | ISR max, one call [µs] "
           "| solve instructions (max) | solve [ms] | solve %% CPU (%g-s windows) |" % window_s,
           "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        star = "" if r["measured"] else " (estimate, not measured)"
        out.append("| %s%s | %g kHz | %d / %d | %.1f-%.1f %% | %.1f-%.1f | %d | %.1f-%.1f | %.2f-%.2f %% |" % (
            r["core"], star, r["fs_hz"] / 1e3, r["isr_instr"], r["isr_max_instr"],
            r["isr_pct"][0], r["isr_pct"][1], r["isr_max_us"][0], r["isr_max_us"][1],
            r["solve_instr"], r["solve_ms"][0], r["solve_ms"][1], r["solve_pct"][0], r["solve_pct"][1]))
    out.append("")
    out.append("Instruction counts: %s. CPI assumed per core:" % source)
    out.append("")
    for c in CORES:
        out.append("* **%s**: ISR %.1f-%.1f, solve %.1f-%.1f cycles per instruction; %s." % (
            c["name"], c["cpi_isr"][0], c["cpi_isr"][1], c["cpi_solve"][0], c["cpi_solve"][1], c["why"]))
    return "\n".join(out) + "\n", rows
