"""What the fixture writers of tests/data share: a fixture folder is written whole or not at all,
and, with a stamp, once per version of its writer.

The writers run as scripts from their own folders (tests/data/CMakeLists.txt, bench/open_models.sh),
so each puts tests/data on sys.path before it imports this module.
"""
import hashlib
import os
import shutil
import tempfile


def stamp_of(paths, extra=""):
    """The SHA-256 (hex) of the contents of the files `paths`, one after the other, then `extra`."""
    digest = hashlib.sha256()
    for path in paths:
        with open(path, "rb") as f:
            digest.update(f.read())
    digest.update(extra.encode())
    return digest.hexdigest()


def write_fixture(out, write, stamp=None):
    """Makes the folder `out` with write(tmp), where tmp is a new folder beside it.

    The folder replaces `out` by a rename once write returns, so that no test reads a half-written
    fixture; if write fails, `out` stays as it was and tmp is removed. With a `stamp`, nothing is
    written when out/.stamp already holds it, and the new folder gets it."""
    out = os.path.abspath(out)
    stamp_path = os.path.join(out, ".stamp")
    if stamp is not None and os.path.exists(stamp_path):
        with open(stamp_path) as f:
            if f.read() == stamp:
                return
    parent = os.path.dirname(out)
    os.makedirs(parent, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="." + os.path.basename(out) + ".", dir=parent)
    try:
        write(tmp)
        if stamp is not None:
            with open(os.path.join(tmp, ".stamp"), "w") as f:
                f.write(stamp)
        shutil.rmtree(out, ignore_errors=True)
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
