"""numba's on-disk cache under sweep (sweep/jitcache.py): two processes (here threads, which flock tells apart the
same way) saving different overloads of one function at once each keep their own data file."""

import threading

from numba.core.caching import IndexDataCacheFile

import sweep.jitcache  # noqa: F401  (serialises numba's cache files on import)


def test_concurrent_saves_of_two_overloads_keep_each_its_own_code(tmp_path, monkeypatch):
    """Both writers read the index before either writes it back (a barrier holds the first until the second has
    read it too, or until 1 s has passed): unserialised, both take data file 1 and one key then names the other's
    code; serialised, the second waits for the first and takes file 2."""
    barrier = threading.Barrier(2, timeout=1.0)
    racing = [True]
    real_load_index = IndexDataCacheFile._load_index

    def load_index_then_wait(self):
        overloads = real_load_index(self)
        if racing[0]:
            try:
                barrier.wait()
            except threading.BrokenBarrierError:  # the other writer is held by the lock: go on alone
                pass
        return overloads

    monkeypatch.setattr(IndexDataCacheFile, "_load_index", load_index_then_wait)
    writers = [threading.Thread(target=IndexDataCacheFile(str(tmp_path), "kernel-1.py311", "stamp").save,
                                args=(key, f"code of {key}")) for key in ("overload a", "overload b")]
    for w in writers:
        w.start()
    for w in writers:
        w.join()
    racing[0] = False
    reader = IndexDataCacheFile(str(tmp_path), "kernel-1.py311", "stamp")
    assert [reader.load(key) for key in ("overload a", "overload b")] == ["code of overload a", "code of overload b"]
