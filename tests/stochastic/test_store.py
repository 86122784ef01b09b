"""The resumable task store: creation, refusals, batched writes (data before status)."""

import numpy as np
import pytest
import zarr

from drillstring.stochastic.execution import TaskOutcome
from drillstring.stochastic.store import DONE, FAILED, PENDING
from drillstring.stochastic.store import ArraySpec, StoreError, TaskStore


class Squares(TaskStore):
    kind = "squares"
    row_dim = "row"
    noun = "rows"

    def __init__(self, path, n, offset=0.0):
        layout = {"x": ArraySpec(("row",), data=np.arange(n, dtype=float)), "y": ArraySpec(("row",)),
                  "series": ArraySpec(("row", "time"), chunk_rows=1)}
        super().__init__(path, case_toml="# none\n", settings={"n": n, "offset": offset}, layout=layout,
                         sizes={"row": n, "time": 3})


class Other(Squares):
    kind = "other"


def test_batched_writes_and_counts(tmp_path):
    store = Squares(tmp_path / "s.zarr", 4)
    assert store.pending() == [0, 1, 2, 3] and store.counts() == (0, 0)
    store.write_many([TaskOutcome(2, DONE, "", {"y": 4.0, "series": np.array([1.0, 2.0, 3.0])}, 0.5),
                      TaskOutcome(0, FAILED, "boom", {}, 0.1)])
    group = zarr.open_group(str(tmp_path / "s.zarr"), mode="r")
    np.testing.assert_array_equal(group["status"][:], [FAILED, PENDING, DONE, PENDING])
    np.testing.assert_array_equal(group["series"][2], [1.0, 2.0, 3.0])
    assert group["y"][2] == 4.0 and np.isnan(group["y"][0]) and group["wall_time"][2] == 0.5
    assert store.failures() == {"0": "boom"} and store.counts() == (1, 1) and store.pending() == [1, 3]
    store.record_session("now", 1.5, 2, 1)
    assert Squares(tmp_path / "s.zarr", 4).sessions() == [{"started": "now", "wall_time": 1.5, "rows": 2,
                                                           "workers": 1}]


def test_a_row_of_fill_values_is_written_and_not_taken_for_damage(tmp_path):
    """A finished row whose value is the fill value (NaN: undefined) has its chunk written, so the store is
    whole, not damaged, when reopened."""
    from drillstring.stochastic.store import damage

    store = Squares(tmp_path / "s.zarr", 2)
    store.write_many([TaskOutcome(0, DONE, "", {"y": np.nan, "series": np.full(3, np.nan)}, 0.5),
                      TaskOutcome(1, DONE, "", {"y": np.nan, "series": np.full(3, np.nan)}, 0.5)])
    assert damage(zarr.open_group(str(tmp_path / "s.zarr"), mode="r")) == []
    assert Squares(tmp_path / "s.zarr", 2).pending() == []


def test_refusals(tmp_path):
    Squares(tmp_path / "s.zarr", 4)
    with pytest.raises(ValueError, match="holds a different squares"):
        Squares(tmp_path / "s.zarr", 4, offset=1.0)
    with pytest.raises(StoreError, match="not a drillstring other store .it is a squares store"):
        Other.open_group(tmp_path / "s.zarr")
    group = zarr.open_group(str(tmp_path / "s.zarr"), mode="a")
    del group["y"]
    with pytest.raises(StoreError, match=r"missing array\(s\): y"):
        Squares(tmp_path / "s.zarr", 4)


class Drawn(Squares):
    """A store with metadata outside the fingerprint (as a study's parameter laws and moments)."""

    def __init__(self, path, n):
        TaskStore.__init__(self, path, case_toml="# none\n", settings={"n": n},
                           layout={"y": ArraySpec(("row",))}, sizes={"row": n},
                           attrs={"parameters": ["weight_on_hook"], "parameter_std": [5000.0]})


def test_metadata_is_checksummed_and_an_edited_digit_is_refused(tmp_path):
    """One digit of the metadata changed in zarr.json (parameter_std 5000 -> 4000, outside the fingerprint:
    it moved a study's ROP ratio from 15.94 to 19.93 unnoticed) is refused by readers and writers alike;
    rows finishing (failures, sessions) do not count as a change."""
    import json

    path = tmp_path / "s.zarr"
    store = Drawn(path, 2)
    store.write_many([TaskOutcome(0, FAILED, "boom", {}, 0.1)])
    store.record_session("now", 1.0, 1, 1)
    Drawn.open_group(path)  # whole: the writers' own attributes are not part of the checksum
    meta = path / "zarr.json"
    text = meta.read_text()
    assert text.count("5000.0") == 1
    meta.write_text(text.replace("5000.0", "4000.0"))
    for open_it in (lambda: Drawn.open_group(path), lambda: Drawn(path, 2)):
        with pytest.raises(StoreError, match="metadata .* changed since the store was created"):
            open_it()
    json.loads(meta.read_text())  # still valid JSON: only the checksum tells
