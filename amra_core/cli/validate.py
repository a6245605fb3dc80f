"""``amra validate [--out DIR] [--quick] [--json]``: run every validation case and write the report.

Progress goes to stderr, the summary table to stdout (``--json``: one strict JSON document instead,
non-finite numbers as ``null``: the report and results paths, counts per status, the failing case
ids and one line per case). The exit code is 0 even when cases fail (the
report says so); bad arguments exit 2 (argparse), as does an output directory that cannot be
written.
"""
from __future__ import annotations

import json
import sys
import time


def cmd_validate(args) -> int:
    from ..validation import run_validation
    from ..validation.report import summary_text
    t0 = time.perf_counter()

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", file=sys.stderr, flush=True)

    try:
        res = run_validation(args.out, quick=args.quick, progress=progress)
    except OSError as exc:
        print(f"amra validate: error: cannot write the report to {args.out!r}: {exc}", file=sys.stderr)
        return 2
    bad = res.failures
    if args.json:
        print(json.dumps(_summary(res), indent=1, ensure_ascii=False, allow_nan=False))
        return 0
    print(summary_text(res.cases))
    print(f"\nreport: {res.html_path}\nresults: {res.json_path}\n"
          f"{len(res.cases)} cases, {len(bad)} failing or in error; {res.meta['wall_time_s']:.0f} s"
          + (f" ({', '.join(c.id for c in bad)})" if bad else ""))
    return 0


def _summary(res) -> dict:
    from ..validation.common import _clean
    from ..validation.report import counts
    cases = res.cases
    return _clean({
        "report": str(res.html_path), "results": str(res.json_path),
        "summary_md": str(res.html_path.with_name("summary.md")),
        "mode": res.meta.get("mode"), "wall_time_s": res.meta.get("wall_time_s"),
        "n_cases": len(cases), "counts": counts(cases), "failures": [c.id for c in res.failures],
        "cases": [{"id": c.id, "section": c.section, "title": c.title, "status": c.status, "value": c.value,
                   "unit": c.unit, "reference": c.reference, "error": c.error} for c in cases],
    })


def register(subparsers) -> None:
    p = subparsers.add_parser("validate", help="run every validation case; write an HTML report and results.json")
    p.add_argument("--out", metavar="DIR", default="validation-report", help="output directory (default: validation-report)")
    p.add_argument("--quick", action="store_true",
                   help="coarser and faster (fewer elements, shorter runs, a 4-column coarse map): about a minute")
    p.add_argument("--quiet", action="store_true", help="no progress messages on stderr")
    p.add_argument("--json", action="store_true",
                   help="print the summary as one JSON document on stdout (non-finite numbers as null)")
    p.set_defaults(func=cmd_validate)
