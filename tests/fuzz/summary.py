"""Summarize a harness run by cause, and write the known-failures list from it.

ASSEMBLER_PIN_FUZZ_REPORT=/tmp/fuzz.json python -m pytest tests/fuzz --runxfail
python tests/fuzz/summary.py /tmp/fuzz.json            # markdown, grouped by cause
python tests/fuzz/summary.py /tmp/fuzz.json --known    # the KNOWN set, to paste
"""

from __future__ import annotations

import json
import re
import sys
from collections import defaultdict

KINDS = {
    "traceback": "CLI tracebacks (an exception escaped main)",
    "non-assembler-error": "API exceptions that are not AssemblerError",
    "hang": "hangs (no answer within the time limit)",
    "wrong-answer": "wrong answers marked valid",
    "accepted": "malformed inputs accepted",
    "noisy-refusal": "refusals that are not one short line (warnings, long lines)",
    "valid-input-refused": "valid inputs refused",
    "exit-status": "exit status disagreeing with the answer",
}


def grouped(results: dict[str, str]) -> dict[str, list[tuple[str, str]]]:
    out: dict[str, list[tuple[str, str]]] = defaultdict(list)
    for case, message in results.items():
        m = re.search(r"\[([a-z-]+)\] (.*)", message)
        kind, text = (m.group(1), m.group(2)) if m else ("other", message)
        out[kind].append((case, text))
    return out


def markdown(results: dict[str, str]) -> str:
    lines = []
    groups = grouped(results)
    for kind in [*KINDS, *sorted(set(groups) - set(KINDS))]:
        if kind not in groups:
            continue
        lines.append(f"### {KINDS.get(kind, kind)}: {len(groups[kind])}\n")
        lines += [f"- `{case}` — {text[:400]}" for case, text in sorted(groups[kind])]
        lines.append("")
    return "\n".join(lines)


if __name__ == "__main__":
    data = json.load(open(sys.argv[1]))
    if "--known" in sys.argv:
        print("KNOWN: set[str] = {")
        for case in sorted(data):
            print(f"    {case!r},")
        print("}")
    else:
        print(markdown(data))
