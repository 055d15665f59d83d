"""The helper arms by link length: kept by their caller, never on the stack model.

Building an arm costs ~15 ms, so :func:`~assembler_pin.helper_arm.initial_condition` keeps
the arms of the link lengths it tried in an :class:`ArmCache`. A caller that wants to own
the cache passes one as ``arms=``; otherwise :func:`arm_cache` gives the default one: a
module-level cache per thread (each arm holds its own mutable ``pin.Data``, so a cache is
never shared between threads), keyed on the content of the configuration the arms depend
on (everything but the payload and gravity, which the helper arm does not use), holding
the caches of the :data:`KEPT_CONFIGURATIONS` most recent configurations.
"""

from __future__ import annotations

import dataclasses
import threading
from collections import OrderedDict

from ..config.schema import AssemblerConfig, PayloadConfig
from ..model.assembler import AssemblerModel
from .arm import HelperArm

__all__ = ["KEPT_ARMS", "KEPT_CONFIGURATIONS", "ArmCache", "arm_cache", "arm_key"]

#: Configurations whose helper arms the default cache of a thread keeps (least recent dropped).
KEPT_CONFIGURATIONS = 8

#: Helper arms (link lengths) one :class:`ArmCache` keeps, least recently used dropped: the
#: scan starts at a link length of the goal's own (its distance / n), so a map of many goals
#: would otherwise keep an arm (~0.25 MB) for every one. An arm holds no state between
#: solves, so building one again gives the same answers.
KEPT_ARMS = 48


class ArmCache:
    """Helper arms by link length, for one configuration; owned by its caller.

    Each arm holds its own mutable ``pin.Data``: a cache must not be shared between threads.
    """

    def __init__(self, config: AssemblerConfig) -> None:
        self.config = config
        self._arms: OrderedDict[float, HelperArm] = OrderedDict()

    def get(self, link_length: float) -> HelperArm:
        """The arm of link length ``link_length`` [m] (rounded to 1e-12 m), built on first use;
        the :data:`KEPT_ARMS` most recently used are kept."""
        key = round(float(link_length), 12)
        arm = self._arms.get(key)
        if arm is None:
            arm = self._arms[key] = HelperArm(self.config, key)
            while len(self._arms) > KEPT_ARMS:
                self._arms.popitem(last=False)
        self._arms.move_to_end(key)
        return arm

    def __len__(self) -> int:
        return len(self._arms)


def arm_key(config: AssemblerConfig) -> AssemblerConfig:
    """The part of ``config`` the helper arms depend on: the configuration with the payload
    and gravity set to their defaults (a hashable, frozen value)."""
    return dataclasses.replace(config, payload=PayloadConfig(), gravity=AssemblerConfig().gravity)


_local = threading.local()


def arm_cache(model_or_config: AssemblerModel | AssemblerConfig) -> ArmCache:
    """The default helper-arm cache of a configuration (or of a model's configuration), for
    the calling thread; the same object for every configuration equal in :func:`arm_key`."""
    cfg = model_or_config.config if isinstance(model_or_config, AssemblerModel) else model_or_config
    caches: OrderedDict[AssemblerConfig, ArmCache] | None = getattr(_local, "caches", None)
    if caches is None:
        caches = _local.caches = OrderedDict()
    key = arm_key(cfg)
    cache = caches.get(key)
    if cache is None:
        cache = caches[key] = ArmCache(key)
        while len(caches) > KEPT_CONFIGURATIONS:
            caches.popitem(last=False)
    caches.move_to_end(key)
    return cache
