"""``assembler-pin bench``: the figures of docs/benchmarks.md.

A leaf: no library module imports it; the command imports the module it needs.
:mod:`.timing` (the median timer, random reachable poses, the goal grid), :mod:`.calls` (the
hot calls, the optimizer, the helper arm, the solve grid), :mod:`.collision` (the clearance,
``solve`` among obstacles), :mod:`.speed` (start-up, threads, the kernels, long stacks),
:mod:`.targets` (the targets run), :mod:`.scaling`, :mod:`.motion`, :mod:`.truss` and
:mod:`.supports`.
"""
