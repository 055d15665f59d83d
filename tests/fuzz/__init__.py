"""The hostile-input harness: every subcommand and every file reader held to the contract.

* :mod:`.corpus` — the curated hostile inputs (files, command lines, API calls).
* :mod:`.harness` — running a command in-process or in a child process (with a watchdog),
  calling the API, and judging the outcome against the contract.
* :mod:`.answers` — independent re-checks of what an answer claims (feasible states,
  trajectory rows, map cells).
* :mod:`.known_failures` — the case ids expected to fail on the code as it is (xfail).

A failure message starts with its kind in brackets — ``[traceback]``, ``[non-assembler-error]``,
``[hang]``, ``[wrong-answer]``, ``[accepted]``, ``[noisy-refusal]``, ``[valid-input-refused]``,
``[exit-status]`` — so a run can be summarized by cause (``pytest tests/fuzz --runxfail -rf``).
"""
