"""The viewer's memory upkeep stays cheap: the heap trim it runs every few seconds finds the C library
once, instead of forking `ldconfig -p` each time (ctypes.util.find_library does that on Linux)."""

import ctypes.util
import subprocess


def test_heap_trim_forks_no_process_after_the_first(monkeypatch):
    import app.guard as guard

    guard._libc.cache_clear()
    looked_up, forked = [], []
    real_find, real_popen = ctypes.util.find_library, subprocess.Popen.__init__
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: looked_up.append(name) or real_find(name))

    def popen(self, *args, **kwargs):
        forked.append(args[0] if args else kwargs.get("args"))
        return real_popen(self, *args, **kwargs)

    guard.big_blocks_go_back()
    monkeypatch.setattr(subprocess.Popen, "__init__", popen)
    for _ in range(5):
        guard.release_memory()
    assert looked_up == ["c"] and forked == []
    assert hasattr(guard._libc(), "malloc_trim")  # glibc here: the trim really runs
