"""Model files, format version 2: compact, bounded reads, consistent state, files others can
read, no debris. (Format basics and fuzzing: test_io.py and test_hostile.py.)"""

from __future__ import annotations

import json
import os
import shutil
import stat
import struct
import time
import tracemalloc
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

import sigmapi
from sigmapi import ModelFileError, SigmaPiSOM, SOMConfig
from sigmapi.checkpoints import list_checkpoints, remove_checkpoints, write_checkpoint
from sigmapi.errors import NumericalError
from sigmapi.io import header_digest, read_archive, write_model
from sigmapi.kernels import BACKENDS

DATA = Path(__file__).resolve().parents[1] / "data"
V1_CFG = dict(map_shape=(3,), x_shape=(4,), y_shape=(5,), iterations=400, seed=7, ordering="none")
"""The config of tests/data/v1-*.npz: written by sigmapi before format version 2 (commit
'tests/data: two model files in format version 1'), after fit(iterations=250)."""


def _small(backend="fast", **kw):
    cfg = SOMConfig(map_shape=(3,), x_shape=(4,), y_shape=(4,), iterations=300, seed=1,
                    backend=backend, **kw)  # fmt: skip
    return SigmaPiSOM(cfg).fit(iterations=200)


# ---------------------------------------------------------------------------- versions, sizes


CROSS_MACHINE_ULPS = {"fast": 0, "reference": 64}
"""How far a v1 file, written on another machine, may be from a fresh fit on this one.

The fast backend's arithmetic is order-fixed and BLAS-free (numba loops without fastmath, so no
reassociation or FMA contraction): bit for bit on every CPU. The reference backend sums through
NumPy's ``einsum`` and ``@`` (OpenBLAS), whose summation order and FMA use follow the CPU's SIMD
path (AVX-512, AVX2, SSE): measured 4 ulps after 250 iterations and 6 after 300 between the
AVX-512 and AVX2 paths (``NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR"``), the
difference an AMD EPYC shows. 64 ulps is ten times that; any change to the rule moves the
weights by orders of magnitude more. Within one machine a round trip stays bit exact
(``test_round_trip_and_continuation_are_bit_exact``)."""


@pytest.mark.parametrize("backend", sorted(p.stem[len("v1-") :] for p in DATA.glob("v1-*.npz")))
def test_version_1_files_still_load_and_continue(backend):
    old = sigmapi.load(DATA / f"v1-{backend}.npz")
    assert old.t_ == 250 and old.backend == backend
    fresh = SigmaPiSOM(**V1_CFG, backend=backend).fit(iterations=250)
    ulps = CROSS_MACHINE_ULPS[backend]
    np.testing.assert_array_max_ulp(old.weights_, fresh.weights_, maxulp=ulps)
    np.testing.assert_array_max_ulp(
        old.partial_fit(iterations=50).weights_,
        fresh.partial_fit(iterations=50).weights_,
        maxulp=ulps,
    )
    assert read_archive(DATA / f"v1-{backend}.npz")[0]["version"] == 1


def test_weights_are_stored_once_in_the_backends_precision(tmp_path):
    fast = _small("fast")
    names = zipfile.ZipFile(fast.save(tmp_path / "f.npz")).namelist()
    assert sorted(names) == ["header.npy", "state_raw.npy", "state_scale.npy"]
    header, arrays = read_archive(tmp_path / "f.npz")
    assert (
        arrays["state_raw"].dtype == np.float32 and header["arrays"]["state_raw"]["dtype"] == "<f4"
    )
    ref = _small("reference")
    assert sorted(zipfile.ZipFile(ref.save(tmp_path / "r.npz")).namelist()) == [
        "header.npy", "weights.npy",
    ]  # fmt: skip
    # about half the v1 size: float32 once instead of float64 plus float32
    v1 = (DATA / "v1-fast.npz").stat().st_size
    assert (tmp_path / "f.npz").stat().st_size < v1


@pytest.mark.parametrize("backend", list(BACKENDS))
@pytest.mark.parametrize("compress", [False, True])
def test_round_trip_and_continuation_are_bit_exact(tmp_path, backend, compress):
    a = _small(backend, winner_rule="min_distance")  # the rule whose norms a state may track
    path = a.save(tmp_path / "m.npz", compress=compress)
    kinds = {i.compress_type for i in zipfile.ZipFile(path).infolist()}
    assert kinds == {zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED}
    b = sigmapi.load(path)
    np.testing.assert_array_equal(a.weights_, b.weights_)
    np.testing.assert_array_equal(
        a.partial_fit(iterations=100).weights_, b.partial_fit(iterations=100).weights_
    )
    # every other backend starts from the same weights
    for other in set(BACKENDS) - {backend}:
        c = sigmapi.load(path, backend=other)
        np.testing.assert_allclose(c.weights_, SigmaPiSOM.load(path).weights_, rtol=1e-7)


def test_float64_reference_weights_round_trip_exactly(tmp_path):
    rng = np.random.default_rng(0)
    cfg = SOMConfig(map_shape=(2,), x_shape=(3,), y_shape=(3,), backend="reference")
    w = rng.standard_normal((2, 3, 3)) * 10.0 ** rng.integers(-300, 20, size=(2, 3, 3))
    som = SigmaPiSOM.from_arrays(
        {"config": cfg.to_dict(), "t": 5, "seed_entropy": "1"}, {"weights": w}
    )
    np.testing.assert_array_equal(sigmapi.load(som.save(tmp_path / "m.npz")).weights_, w)


# ---------------------------------------------------------------------------- bounded reads


def _peak(fn):
    """(outcome, peak traced bytes, seconds) of ``fn()``; outcome is the error or 'loaded'."""
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        fn()
        out: object = "loaded"
    except ModelFileError as exc:
        out = exc
    dt = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return out, peak, dt


def _zeros_member(zf, name, nbytes, prefix=b""):
    with zf.open(name, "w", force_zip64=True) as m:
        m.write(prefix)
        block = bytes(1 << 20)
        for _ in range(nbytes >> 20):
            m.write(block)


LIMIT = 100 * 1024 * 1024  # the acceptance: 100 MB over the file's valid content


def test_an_extra_member_that_inflates_to_a_gigabyte_is_never_read(tmp_path):
    good = _small("reference").save(tmp_path / "good.npz")
    for name in ("junk.npy", "state_junk.npy"):
        bomb = tmp_path / f"{name}.npz"
        shutil.copy(good, bomb)
        with zipfile.ZipFile(bomb, "a", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
            _zeros_member(zf, name, 1 << 30)
        assert bomb.stat().st_size < (1 << 30) // 100  # inflates 100-fold and more
        out, peak, dt = _peak(lambda b=bomb: sigmapi.load(b))
        assert isinstance(out, ModelFileError) and ("junk" in str(out)), out
        assert peak < LIMIT and dt < 1.0, (peak, dt)


def test_a_header_that_inflates_to_a_gigabyte_is_never_read(tmp_path):
    bomb = tmp_path / "h.npz"
    npy = b"\x93NUMPY\x01\x00" + struct.pack("<H", 118)
    npy += (b"{'descr': '|u1', 'fortran_order': False, 'shape': (1073741824,), }").ljust(
        117
    ) + b"\n"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
        _zeros_member(zf, "header.npy", 1 << 30, npy)
    out, peak, dt = _peak(lambda: sigmapi.load(bomb))
    assert isinstance(out, ModelFileError) and "at most 1048576 bytes" in str(out), out
    assert peak < LIMIT and dt < 1.0, (peak, dt)


def _forged(path, header, arrays_npy):
    """A file whose header is re-checksummed (a forger's file), members as raw npy bytes."""
    header = {**header, "header_sha256": ""}
    header["header_sha256"] = header_digest(header)
    head = json.dumps(header, sort_keys=True).encode()
    with zipfile.ZipFile(path, "w") as zf:
        with zf.open("header.npy", "w") as m:
            np.lib.format.write_array(m, np.frombuffer(head, np.uint8))
        for name, data in arrays_npy.items():
            zf.writestr(name, data)
    return path


def _npy_prefix(descr, shape):
    d = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode()
    d = d.ljust(117) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(d)) + d


def test_a_huge_declared_shape_is_refused_before_allocating(tmp_path):
    som = _small("reference")
    header, _ = som.to_arrays()
    huge = (10**7, 10**3, 10**3)  # 8e13 bytes: 80 TB
    cfg = {**header["config"], "map_shape": [10**7], "x_shape": [10**3], "y_shape": [10**3]}
    decl = {"weights": {"dtype": "<f8", "shape": list(huge), "sha256": "0"}}
    forged = {**header, "format": "sigmapi-model", "version": 2, "config": cfg, "arrays": decl}
    path = _forged(tmp_path / "huge.npz", forged, {"weights.npy": _npy_prefix("<f8", huge)})
    assert path.stat().st_size < 4096
    out, peak, dt = _peak(lambda: sigmapi.load(path))
    assert isinstance(out, ModelFileError) and "needs about 80 TB" in str(out), out
    assert peak < LIMIT and dt < 1.0
    # a member larger than the config allows is refused from the header alone
    forged["config"] = header["config"]
    forged["arrays"] = {"state_raw": {"dtype": "<f4", "shape": [10**6], "sha256": "0"}}
    path = _forged(tmp_path / "big.npz", forged, {"state_raw.npy": _npy_prefix("<f4", (10**6,))})
    with pytest.raises(ModelFileError, match="larger than the config's 48 weights"):
        sigmapi.load(path)


def test_a_declared_shape_the_member_does_not_hold_is_refused(tmp_path):
    header, _ = _small("reference").to_arrays()
    decl = {"weights": {"dtype": "<f8", "shape": [3, 4, 4], "sha256": "0"}}
    full = {**header, "format": "sigmapi-model", "version": 2, "arrays": decl}
    npy = _npy_prefix("<f8", (3, 4, 4)) + bytes(8 * 48 - 8)  # 8 bytes short
    with pytest.raises(ModelFileError, match="holds 504 bytes, its npy header declares 512"):
        sigmapi.load(_forged(tmp_path / "s.npz", full, {"weights.npy": npy}))


def test_duplicate_members_are_refused(tmp_path):
    path = _small("reference").save(tmp_path / "m.npz")
    with zipfile.ZipFile(path) as zf:
        data = zf.read("weights.npy")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns about the duplicate name
        with zipfile.ZipFile(path, "a") as zf:
            zf.writestr("weights.npy", data)
    with pytest.raises(ModelFileError, match=r"'weights\.npy' appears twice"):
        sigmapi.load(path)


def _npy_header_spans(path):
    """(offset, length) in the file of every member's npy header (stored members)."""
    raw = path.read_bytes()
    spans = []
    for info in zipfile.ZipFile(path).infolist():
        off = info.header_offset
        name_len, extra_len = struct.unpack("<HH", raw[off + 26 : off + 30])
        start = off + 30 + name_len + extra_len
        (n,) = struct.unpack("<H", raw[start + 8 : start + 10])
        spans.append((start, 10 + n))
    return spans


def _flip_each(data, flips, bad, weights):
    """Load ``data`` with each (position, bit) flipped in turn: a clean refusal or the same
    weights, never another exception. Returns the counts of both outcomes."""
    outcomes = {"refused": 0, "loaded": 0}
    for pos, bit in flips:
        data[pos] ^= 1 << bit
        bad.write_bytes(bytes(data))
        data[pos] ^= 1 << bit
        try:
            m = sigmapi.load(bad)
        except ModelFileError:
            outcomes["refused"] += 1
            continue
        outcomes["loaded"] += 1
        np.testing.assert_array_equal(m.weights_, weights)
    return outcomes


def test_every_bit_of_every_npy_header_flipped_is_refused_or_harmless(tmp_path):
    som = _small("fast", winner_rule="min_distance")  # three members: raw, scale, sqnorm
    path = som.save(tmp_path / "m.npz")
    raw = bytearray(path.read_bytes())
    spans = _npy_header_spans(path)
    assert len(spans) == 4
    flips = [(pos, bit) for a, n in spans for pos in range(a, a + n) for bit in range(8)]
    outcomes = _flip_each(raw, flips, tmp_path / "f.npz", som.weights_)
    assert sum(outcomes.values()) == 8 * sum(n for _, n in spans)


@pytest.mark.parametrize("method", [zipfile.ZIP_DEFLATED, zipfile.ZIP_LZMA])
def test_flipped_bits_in_compressed_streams_are_refused_or_harmless(tmp_path, method):
    som = _small("fast")
    path = som.save(tmp_path / "m.npz")
    packed = tmp_path / "p.npz"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(packed, "w", compression=method) as dst:
        for info in src.infolist():
            dst.writestr(info.filename, src.read(info.filename))
    np.testing.assert_array_equal(sigmapi.load(packed).weights_, som.weights_)
    data = bytearray(packed.read_bytes())
    rng = np.random.default_rng(2024)  # seeded: every position is equally likely
    flips = [(int(rng.integers(len(data))), int(rng.integers(8))) for _ in range(400)]
    outcomes = _flip_each(data, flips, tmp_path / "f.npz", som.weights_)
    assert outcomes["refused"] > 0


# ---------------------------------------------------------------------------- consistency


def _rewrite_v1(tmp_path, change):
    """The v1 fast fixture with ``change(arrays)`` applied and every checksum redone."""
    header, arrays = read_archive(DATA / "v1-fast.npz")
    change(arrays)
    from sigmapi.io import digest, encode_archive

    header["sha256"] = digest(arrays["weights"])
    header["state_sha256"] = {k[6:]: digest(v) for k, v in arrays.items() if k != "weights"}
    header["header_sha256"] = header_digest(header)
    path = tmp_path / "v1.npz"
    path.write_bytes(encode_archive(header, arrays))
    return path


def test_backend_state_that_disagrees_with_the_weights_is_refused(tmp_path):
    def scale(a):
        a["state_scale"] = a["state_scale"] * 2.0

    with pytest.raises(ModelFileError, match="disagrees with the stored weights"):
        sigmapi.load(_rewrite_v1(tmp_path, scale))
    assert sigmapi.load(_rewrite_v1(tmp_path, lambda a: None)).t_ == 250


def test_raw_times_scale_overflow_is_refused(tmp_path):
    header, arrays = _small("fast").to_arrays()
    arrays["state_raw"] = np.full_like(arrays["state_raw"], 1e30)
    arrays["state_scale"] = np.full_like(arrays["state_scale"], 1e300)
    path = write_model(tmp_path / "o.npz", header, arrays)
    with pytest.raises(ModelFileError, match="overflow such as raw x scale"):
        sigmapi.load(path)
    arrays["state_scale"][:] = 1.0
    arrays["state_raw"][0, 0] = 3e38  # finite in float32, beyond what training can reach
    with pytest.raises(ModelFileError, match="magnitude <= 1e"):
        sigmapi.load(write_model(tmp_path / "p.npz", header, arrays))


def test_a_model_never_saves_a_file_load_would_refuse(tmp_path):
    som = _small("fast")
    som._run.state.raw[0, 0] = np.inf  # what an overflow in training would leave
    with pytest.raises(NumericalError, match="state_raw hold NaN or inf"):
        som.save(tmp_path / "m.npz")
    som._run.state.raw[0, 0] = 3e38  # finite float32, but weights load refuses
    with pytest.raises(NumericalError, match=r"beyond 1e\+30"):
        som.save(tmp_path / "m.npz")
    assert not any(tmp_path.iterdir())
    # the points where an overflow could start are refused with their cause
    with pytest.raises(sigmapi.ConfigError, match="init_scale"):
        SOMConfig(init_scale=1e39)
    fresh = SigmaPiSOM(map_shape=(3,), x_shape=(4,), y_shape=(4,), backend="fast")
    big = np.full((5, 4), 1e20)
    with pytest.raises(ValueError, match=r"\|x1_i y1_j\| <= 1e\+15 .* got up to 1e\+40"):
        fresh.partial_fit(views=(big, big, big, big))
    header, arrays = _small("reference").to_arrays()
    arrays["weights"] = np.full_like(arrays["weights"], 1e39)  # finite float64, not float32
    with pytest.raises(ModelFileError, match="magnitude <= 1e"):
        SigmaPiSOM.from_arrays({**header, "backend": "other"}, arrays, backend="fast")


# ---------------------------------------------------------------------------- modes, debris


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600)])
def test_files_follow_the_umask_and_overwrites_keep_the_mode(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        path = _small("reference").save(tmp_path / "m.npz")
        assert stat.S_IMODE(path.stat().st_mode) == mode
        write_checkpoint(_small("reference"), tmp_path / "c.ckpt")
        ckpt = list_checkpoints(tmp_path / "c.ckpt")[0][1]
        assert stat.S_IMODE(ckpt.stat().st_mode) == mode
        path.chmod(0o640)
        _small("reference").save(path)
        assert stat.S_IMODE(path.stat().st_mode) == 0o640
    finally:
        os.umask(old)


def test_devices_and_fifos_are_never_replaced(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(ModelFileError, match="not a regular file"):
        _small("reference").save(fifo)
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pipe"]


def test_stale_temp_files_are_removed_and_only_ours(tmp_path):
    som = _small("reference")
    stale = tmp_path / ".m.npz.abcd1234.tmp"
    fresh = tmp_path / ".m.npz.efgh5678.tmp"  # another writer, still busy
    other = tmp_path / ".m.npz.notours.tmp"
    for p in (stale, fresh, other):
        p.write_bytes(b"x")
    os.utime(stale, (time.time() - 3600, time.time() - 3600))
    os.utime(other, (time.time() - 3600, time.time() - 3600))
    som.save(tmp_path / "m.npz")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["m.npz", fresh.name, other.name])
    folder = tmp_path / "m.npz.ckpt"
    folder.mkdir()
    old_ckpt = folder / ".step-000000001000.npz.x1y2z3w4.tmp"
    old_ckpt.write_bytes(b"x")
    os.utime(old_ckpt, (time.time() - 3600, time.time() - 3600))
    write_checkpoint(som, folder)
    assert [p.name for p in folder.iterdir()] == ["step-000000000200.npz"]


def test_a_symlinked_checkpoint_folder_is_refused_and_never_pruned(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    theirs = [elsewhere / f"step-{i:012d}.npz" for i in range(1, 6)]
    for p in theirs:
        p.write_bytes(b"not ours")
    link = tmp_path / "m.npz.ckpt"
    link.symlink_to(elsewhere)
    with pytest.raises(ModelFileError, match="symbolic link"):
        write_checkpoint(_small("reference"), link)
    with pytest.raises(ModelFileError, match="symbolic link"):
        remove_checkpoints(link)
    assert all(p.read_bytes() == b"not ours" for p in theirs)


def test_remove_checkpoints_leaves_other_files(tmp_path):
    folder = tmp_path / "m.npz.ckpt"
    som = _small("reference")
    write_checkpoint(som, folder)
    assert remove_checkpoints(folder) == 1 and not folder.exists()
    write_checkpoint(som, folder)
    (folder / "notes.txt").write_text("mine")
    assert remove_checkpoints(folder) == 1
    assert [p.name for p in folder.iterdir()] == ["notes.txt"]
