"""
The interpreter's full garbage collections, kept out of the world's service calls.

A full collection (generation 2) walks every object the process holds: about 130,000 in a world
of 50 tinybots (the imports, the models, their ROS interfaces), 90 to 200 ms on this kind of
machine, and CPython starts one wherever an allocation happens to cross its threshold, inside a
spawn or a tick. While a world node lives, the objects of its start-up are frozen (gc.freeze:
they are never walked again) and CPython starts no full collection of its own; the world's tick
runs one when CPython would have (its count past the threshold), between two executor turns,
so that no answer waits for it. Collections of the young generations stay automatic: they walk
only what was made since the last one.

Objects frozen are not collected: garbage cycles left by models of the start-up that are deleted
later stay in memory (once), and so the freeze is undone when the last world node goes.
"""

import gc
import time

# CPython's count of generation 2 never reaches it: no automatic full collection.
NEVER = 2 ** 31 - 1
# At most this share of the wall time goes to full collections, however often they fall due.
MOST_TIME_SHARE = 0.01


class CollectionsBetweenTicks:
    """Full collections of the process, held back from calls and run by the world's ticks."""

    _living = 0  # world nodes of this process that hold the collections back
    _thresholds = None  # CPython's thresholds before the first of them

    def __init__(self, *, wall_clock=time.monotonic):
        """Freeze what the process holds now and hold CPython's own full collections back."""
        cls = type(self)
        if cls._living == 0:
            cls._thresholds = gc.get_threshold()
        cls._living += 1
        self._full_threshold = cls._thresholds[2]
        self._wall_clock = wall_clock
        self._next_allowed = 0.0  # wall time
        self._closed = False
        gc.freeze()
        young, middle, _ = cls._thresholds
        gc.set_threshold(young, middle, NEVER)

    def collect_if_due(self):
        """Run a full collection if CPython would have by now; return whether it ran."""
        if gc.get_count()[2] <= self._full_threshold or not gc.isenabled():
            return False
        start = self._wall_clock()
        if start < self._next_allowed:
            return False
        gc.collect(2)
        took = self._wall_clock() - start
        self._next_allowed = start + took / MOST_TIME_SHARE
        return True

    def close(self):
        """Give CPython its own full collections back once the last world node is gone."""
        if self._closed:
            return
        self._closed = True
        cls = type(self)
        cls._living -= 1
        if cls._living == 0:
            gc.set_threshold(*cls._thresholds)
            gc.unfreeze()
