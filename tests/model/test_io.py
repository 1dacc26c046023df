"""Model files: exact round trips (property-based), atomic writes, no pickle, clean errors."""

from __future__ import annotations

import json
import pickle
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sigmapi
from sigmapi import ModelFileError, SigmaPiSOM, SOMConfig
from sigmapi.io import encode_archive, read_archive

shapes = st.lists(st.integers(1, 4), min_size=1, max_size=2).map(tuple)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    map_shape=shapes,
    n_in=st.integers(1, 4),
    ndim=st.integers(1, 2),
    t=st.integers(0, 10**9),
    seed=st.one_of(st.none(), st.integers(0, 2**63)),
    data=st.data(),
)
def test_round_trip_is_exact(tmp_path, map_shape, n_in, ndim, t, seed, data):
    cfg = SOMConfig(map_shape=map_shape, x_shape=(n_in,) * ndim, y_shape=(n_in + 1,) * ndim,
                    seed=seed, backend="reference", iterations=7)  # fmt: skip
    k = int(np.prod(map_shape))
    w = np.asarray(
        data.draw(
            st.lists(
                st.floats(-1e6, 1e6),
                min_size=k * n_in**ndim * (n_in + 1) ** ndim,
                max_size=k * n_in**ndim * (n_in + 1) ** ndim,
            )
        )
    ).reshape(k, n_in**ndim, (n_in + 1) ** ndim)
    entropy = str(SigmaPiSOM(cfg).seed_entropy)
    som = SigmaPiSOM.from_arrays(
        {"config": cfg.to_dict(), "t": t, "seed_entropy": entropy}, {"weights": w}
    )
    path = som.save(tmp_path / "m.npz")
    back = sigmapi.load(path)
    np.testing.assert_array_equal(back.weights_, w)
    assert back.t_ == t and back.config == cfg and back.seed_entropy == som.seed_entropy


def test_atomic_write_leaves_no_temp_files(tmp_path, small_1d):
    som = SigmaPiSOM(small_1d).fit(iterations=10)
    som.save(tmp_path / "m.npz")
    som.save(tmp_path / "m.npz")  # overwrite in place
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.npz"]


def _saved(tmp_path, small_1d):
    return SigmaPiSOM(small_1d).fit(iterations=10).save(tmp_path / "m.npz")


def test_truncated_file_fails_cleanly(tmp_path, small_1d):
    data = _saved(tmp_path, small_1d).read_bytes()
    for cut in (0, 10, len(data) // 2, len(data) - 1):
        bad = tmp_path / f"cut{cut}.npz"
        bad.write_bytes(data[:cut])
        with pytest.raises(ModelFileError):
            sigmapi.load(bad)


def test_flipped_weight_bit_fails_the_checksum(tmp_path, small_1d):
    path = _saved(tmp_path, small_1d)
    header, arrays = read_archive(path)
    w = arrays["weights"].copy()
    w.reshape(-1).view(np.uint8)[100] ^= 0x10
    (tmp_path / "f.npz").write_bytes(encode_archive(header, {"weights": w}))
    with pytest.raises(ModelFileError, match="checksum"):
        sigmapi.load(tmp_path / "f.npz")


def test_pickled_payload_is_refused_and_never_run(tmp_path):
    class Boom:
        def __reduce__(self):
            return (open, (str(tmp_path / "pwned"), "w"))

    path = tmp_path / "evil.npz"
    np.savez(path, header=np.array([Boom()], dtype=object), weights=np.zeros((1, 1, 1)))
    with pytest.raises(ModelFileError, match="pickle"):
        sigmapi.load(path)
    assert not (tmp_path / "pwned").exists()
    raw = tmp_path / "raw.npz"
    raw.write_bytes(pickle.dumps({"weights": 1}))
    with pytest.raises(ModelFileError):
        sigmapi.load(raw)


def test_wrong_version_shape_and_nan_are_named(tmp_path, small_1d):
    path = _saved(tmp_path, small_1d)
    header, arrays = read_archive(path)
    cases = {
        "version": ({**header, "version": 99}, arrays),
        "shape": (header, {"weights": arrays["weights"][:, :3]}),
        "NaN": (header, {"weights": np.full_like(arrays["weights"], np.nan)}),
        "format": ({**header, "format": "something-else"}, arrays),
        "lacks": ({k: v for k, v in header.items() if k != "t"}, arrays),
    }
    for match, (h, a) in cases.items():
        p = tmp_path / f"{match}.npz"
        p.write_bytes(encode_archive(h, a))
        with pytest.raises(ModelFileError, match=match):
            sigmapi.load(p)


def test_not_a_zip_and_missing_file(tmp_path):
    (tmp_path / "t.npz").write_text("hello")
    with pytest.raises(ModelFileError):
        sigmapi.load(tmp_path / "t.npz")
    with pytest.raises(ModelFileError, match="does not exist"):
        sigmapi.load(tmp_path / "none.npz")
    with zipfile.ZipFile(tmp_path / "z.npz", "w") as z:
        z.writestr("header.npy", b"\x93NUMPY garbage")
    with pytest.raises(ModelFileError):
        sigmapi.load(tmp_path / "z.npz")


def test_to_arrays_from_arrays_and_replay_twin(small_1d):
    som = SigmaPiSOM(small_1d).fit(iterations=1500)
    header, arrays = som.to_arrays()
    assert json.loads(json.dumps(header)) == header
    back = SigmaPiSOM.from_arrays(header, arrays)
    np.testing.assert_array_equal(back.weights_, som.weights_)
    assert back.t_ == som.t_ and back.seed_entropy == som.seed_entropy
    twin = som.replay_twin()
    assert not twin.is_fitted and twin.config == som.config
    np.testing.assert_array_equal(twin.fit(iterations=som.t_).weights_, som.weights_)
    with pytest.raises(ModelFileError, match="the config needs"):
        SigmaPiSOM.from_arrays(header, {"weights": arrays["weights"][:, :3]})


def test_header_is_readable_json(tmp_path, small_1d):
    header, _ = read_archive(_saved(tmp_path, small_1d))
    assert header["format"] == "sigmapi-model" and header["version"] == 2
    assert json.loads(json.dumps(header)) == header
