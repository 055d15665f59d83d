"""Reading JSON inputs and plate files for the ``assembler-pin`` subcommands.

Every value is refused with one :class:`~assembler_pin.exceptions.CLIError` line naming
what was wrong: text that is not UTF-8 or not JSON, keys given twice, non-finite numbers,
matrices that are not 4×4 numbers or not poses. Nothing heavy is imported at module level.
"""

from __future__ import annotations

import json
import math
import sys

from ..config.inputs import read_input_bytes
from ..config.numbers import finite_float
from ..exceptions import CLIError, short_repr

__all__ = ["MAX_JSON_BYTES", "plates_from_file", "read_json"]


#: Largest JSON input read [bytes]: a plate file of 64 platforms is under 20 kB.
MAX_JSON_BYTES = 16 << 20


def _refuse_constant(name: str) -> float:
    raise CLIError(f"{name} is not a number JSON allows (write finite numbers)")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise CLIError(f"the number {text[:30]} is out of range (it overflows a float)")
    return value


def _unique_keys(pairs: list[tuple[str, object]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise CLIError(f"the key {json.dumps(key)[:40]} is given twice in one object")
        out[key] = value
    return out


def read_json(source: str) -> object:
    """Strict JSON from a file or stdin (``-``): no NaN/Infinity literals, no number that
    overflows a float, no key given twice in an object; at most :data:`MAX_JSON_BYTES`.

    Raises:
        CLIError: one line naming ``source``.
    """
    try:
        if source == "-":
            raw = sys.stdin.buffer.read(MAX_JSON_BYTES + 1) if hasattr(sys.stdin, "buffer") else sys.stdin.read()
        else:  # the one door of input files: a FIFO or a device is refused before it is opened
            raw = read_input_bytes(source, "plate file", CLIError, MAX_JSON_BYTES)
        text = raw.decode("utf-8") if isinstance(raw, bytes) else raw
    except OSError as exc:
        raise CLIError(f"cannot read '{source}': {exc.strerror or exc}") from None
    except (UnicodeDecodeError, ValueError):
        raise CLIError(f"'{source}' is not UTF-8 text") from None
    if len(text) > MAX_JSON_BYTES:
        raise CLIError(f"'{source}' is larger than {MAX_JSON_BYTES} bytes")
    try:
        return json.loads(
            text, object_pairs_hook=_unique_keys, parse_constant=_refuse_constant, parse_float=_finite_float
        )
    except CLIError as exc:
        raise CLIError(f"'{source}': {exc}") from None
    except json.JSONDecodeError as exc:
        raise CLIError(f"'{source}' is not valid JSON: {exc}") from None
    except RecursionError:
        raise CLIError(f"'{source}' is nested too deeply to be a plate file") from None
    except ValueError as exc:  # e.g. an integer of more digits than Python converts
        raise CLIError(f"'{source}' holds a number that cannot be read: {str(exc)[:80]}") from None


def _plate_matrix(k: int, plate: object) -> list[list[float]]:
    """Plate ``k`` of a plate file as a 4×4 list of floats, refusing anything that is not."""
    where = f"plate {k}"
    if not (isinstance(plate, list) and len(plate) == 4 and all(isinstance(r, list) and len(r) == 4 for r in plate)):
        raise CLIError(f"{where} must be a 4x4 matrix (a list of 4 rows of 4 numbers)")
    for row in plate:
        for x in row:
            if isinstance(x, bool) or not isinstance(x, (int, float)):
                shown = json.dumps(x)[:30]
                raise CLIError(f"{where}: {shown} is not a number (write numbers, not strings or true/false)")
            if finite_float(x) is None:  # an integer too large for a float, as 1e999
                raise CLIError(f"{where}: {short_repr(x, 30)} is not a finite number")
    return [[float(x) for x in row] for row in plate]


def plates_from_file(source: str) -> list:
    """The ``plates`` list of a JSON plate file (``{"plates": [n+1 4x4 world transforms]}``),
    every matrix checked: 4×4 finite numbers (not strings, booleans or null), then as every
    pose is (:func:`~assembler_pin.kinematics.checked_rotations`): bottom row [0, 0, 0, 1] (to
    1e-12) and a rotation block (orthonormal, det +1, to
    :data:`~assembler_pin.kinematics.ORTHONORMAL_TOL`).

    Raises:
        CLIError: one line naming the plate index.
    """
    plates = _plates_of_document(read_json(source))
    if not isinstance(plates, list) or not plates:
        raise CLIError('"plates" must be a list of n+1 4x4 matrices, plate 0 first')
    if len(plates) > 65:
        raise CLIError(f'"plates" holds {len(plates)} matrices; a stack has at most 65 plates (64 platforms)')
    out = [_plate_matrix(k, plate) for k, plate in enumerate(plates)]
    _check_rotations(out)
    return out


def _check_rotations(matrices: list[list[list[float]]]) -> None:
    """The plates' bottom rows and rotation blocks, by the package's one pose check.

    Raises:
        CLIError: its message, naming the first plate that fails.
    """
    import numpy as np

    from ..exceptions import PoseError
    from ..kinematics.poses import checked_rotations

    try:
        checked_rotations(np.array(matrices), "plate")
    except PoseError as exc:
        raise CLIError(str(exc)) from None


def _plates_of_document(doc: object) -> object:
    """The plates of a plate file, or of a ``solve --json`` answer (its optimized pose, else the
    helper arm's), which is accepted only when it says ``success: true``."""
    if isinstance(doc, dict) and "plates" in doc:
        return doc["plates"]
    if isinstance(doc, dict) and "goal" in doc and ("optimized" in doc or "initial" in doc):
        if doc.get("success") is not True:
            raise CLIError("the solve answer holds no valid pose (its success is not true): solve a reachable goal")
        for key in ("optimized", "initial"):
            state = doc.get(key)
            if isinstance(state, dict) and "plates" in state:
                return state["plates"]
    raise CLIError('the input must be a JSON object {"plates": [n+1 4x4 world transforms]} or a solve --json answer')
