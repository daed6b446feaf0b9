"""The artefact store: content hashes, atomic writes, provenance, documents."""

from __future__ import annotations

import os

import h5py
import numpy as np
import pytest

from artic_cli.errors import ArticError
from artic_cli.io.fingerprint import h5_content_hash
from artic_cli.io.store import (Provenance, atomic_h5, read_doc, stored_content_hash, stored_recipe, write_doc)


def _write(path, value, stage="s"):
    with atomic_h5(path, "test", Provenance(stage=stage, params={"v": value})) as f:
        f.create_dataset("x", data=np.arange(5.0) * value).attrs["units"] = "cm"
        f.attrs["note"] = "held"


def test_content_hash_sees_what_is_held_not_where_it_came_from(tmp_path):
    a, b, c = tmp_path / "a.h5", tmp_path / "b.h5", tmp_path / "c.h5"
    _write(a, 1.0, stage="one")
    _write(b, 1.0, stage="two")  # other provenance, same content
    _write(c, 2.0)
    assert stored_content_hash(a) == stored_content_hash(b) != stored_content_hash(c)
    assert stored_recipe(a) != stored_recipe(b)
    with h5py.File(a, "r") as f:
        assert h5_content_hash(f) == f.attrs["content_sha256"]
    with h5py.File(b, "r+") as f:
        f["x"][2] = 99.0
        assert h5_content_hash(f) != f.attrs["content_sha256"]


def test_an_unchanged_rewrite_keeps_the_file_time_and_a_changed_one_does_not(tmp_path):
    a = tmp_path / "a.h5"
    _write(a, 1.0)
    os.utime(a, ns=(10**18, 10**18))
    _write(a, 1.0, stage="again")
    assert os.stat(a).st_mtime_ns == 10**18 and stored_recipe(a) == Provenance("again", params={"v": 1.0}).recipe
    _write(a, 3.0)
    assert os.stat(a).st_mtime_ns != 10**18


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    a = tmp_path / "a.h5"
    _write(a, 1.0)
    before = stored_content_hash(a)
    with pytest.raises(RuntimeError):
        with atomic_h5(a, "test") as f:
            f.create_dataset("x", data=[1.0])
            raise RuntimeError("interrupted")
    assert stored_content_hash(a) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.h5"]


def test_documents_round_trip_with_provenance_and_keep_their_time(tmp_path):
    for name in ("t.json", "t.yaml"):
        p = tmp_path / name
        write_doc(p, {"rows": [{"ours": 1.5}]}, Provenance("s"))
        doc = read_doc(p, "table", "rerun it")
        assert doc["rows"] == [{"ours": 1.5}] and len(doc["provenance"]["content_sha256"]) == 64
        os.utime(p, ns=(10**18, 10**18))
        write_doc(p, {"rows": [{"ours": 1.5}]}, Provenance("other"))
        assert os.stat(p).st_mtime_ns == 10**18 and read_doc(p, "t", "h")["provenance"]["recipe_sha256"] == \
            Provenance("other").recipe
    (tmp_path / "x.json").write_text("[1, 2]")
    with pytest.raises(ArticError, match="not a table written by this artic; rerun it"):
        read_doc(tmp_path / "x.json", "table", "rerun it")
    (tmp_path / "y.json").write_text("{broken")
    with pytest.raises(ArticError, match="damaged"):
        read_doc(tmp_path / "y.json", "table", "rerun it")
