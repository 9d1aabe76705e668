"""Where the suite's cold-cache time goes: every compile, trace and lowering, by test and function.

    OCTAX_COMPILE_LOG=/tmp/compiles.tsv make test        # each pytest process appends its lines
    python tests/compile_log.py /tmp/compiles.tsv [--top 30]

A cold run of `make test` is mostly XLA compiling programs that a warm run reads from JAX's
persistent cache; tracing and lowering are paid on every run. Summing the events JAX already
reports (`jax.monitoring` durations, with the function's name) by test file, by test and by
function shows which programs to share between tests, which is how the suite gets faster
without testing less.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys

EVENTS = {"/jax/core/compile/backend_compile_duration": "compile",
          "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower",
          "/jax/core/compile/jaxpr_trace_duration": "trace"}


def record_compiles(path: str) -> None:
    """Appends `test<TAB>event<TAB>function<TAB>seconds` to `path` for each of JAX's compile-time events."""
    import jax

    def listener(event: str, seconds: float, **kwargs) -> None:
        kind = EVENTS.get(event)
        if kind is None:
            return
        test = os.environ.get("PYTEST_CURRENT_TEST", "(collection)").rsplit(" (", 1)[0]
        with open(path, "a") as f:
            f.write(f"{test}\t{kind}\t{kwargs.get('fun_name', '?')}\t{seconds:.4f}\n")

    jax.monitoring.register_event_duration_secs_listener(listener)


def summarize(path: str, top: int) -> str:
    by_file: collections.Counter = collections.Counter()
    by_test: collections.Counter = collections.Counter()
    by_function: collections.Counter = collections.Counter()
    by_kind: collections.Counter = collections.Counter()
    counts: collections.Counter = collections.Counter()
    with open(path) as f:
        for line in f:
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 4:
                continue
            test, kind, function, seconds = parts[0], parts[1], parts[2], float(parts[3])
            by_kind[kind] += seconds
            counts[kind] += 1
            by_file[test.split("::")[0], kind] += seconds
            by_test[test, kind] += seconds
            by_function[function, kind] += seconds
    lines = ["total: " + ", ".join(f"{kind} {by_kind[kind]:.0f} s ({counts[kind]} events)" for kind in sorted(by_kind))]
    for title, table in (("by file", by_file), ("by test", by_test), ("by function", by_function)):
        lines.append(f"\n{title} (compile seconds; trace + lower after the slash)")
        totals: collections.Counter = collections.Counter()
        for (name, kind), seconds in table.items():
            totals[name] += 0.0
            if kind == "compile":
                totals[name] += seconds
        for name, seconds in totals.most_common(top):
            other = table.get((name, "trace"), 0.0) + table.get((name, "lower"), 0.0)
            lines.append(f"{seconds:8.1f} / {other:6.1f}  {name}")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("log")
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args(argv)
    print(summarize(args.log, args.top))
    return 0


if __name__ == "__main__":
    sys.exit(main())
