"""Leaves without domain logic, imported by every layer above :mod:`~assembler_pin.config`:
files written atomically (:mod:`.files`), progress callbacks (:mod:`.progress`), BLAS threads
(:mod:`.threads`), signals (:mod:`.signals`), small linear algebra (:mod:`.linalg`), the colours
(:mod:`.palette`), one-line messages (:mod:`.messages`), input validation (:mod:`.validation`),
machine names (:mod:`.naming`) and the labels a person reads (:mod:`.labels`).

Import from the modules; this package re-exports nothing.
"""
