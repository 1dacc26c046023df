"""Nothing trusted: fuzzed model files and configs fail cleanly; nothing is ever executed."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sigmapi
from sigmapi import ConfigError, ModelFileError, SigmaPiSOM, SOMConfig
from sigmapi.config import apply_overrides, load_config_file

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))


@pytest.fixture(scope="module")
def good_file(tmp_path_factory):
    cfg = SOMConfig(map_shape=(3,), x_shape=(4,), y_shape=(4,), iterations=50, seed=1,
                    backend="reference")  # fmt: skip
    som = SigmaPiSOM(cfg).fit()
    path = som.save(tmp_path_factory.mktemp("good") / "m.npz")
    return path, som.weights_.copy()


def _load_or_clean_error(path, original=None):
    try:
        m = sigmapi.load(path)
    except ModelFileError:
        return "refused"
    # a change that the format does not cover (e.g. a zip timestamp) must not change the model
    if original is not None:
        np.testing.assert_array_equal(m.weights_, original)
    return "loaded"


def test_truncation_at_every_byte_fails_cleanly(good_file, tmp_path):
    path, _ = good_file
    data = path.read_bytes()
    bad = tmp_path / "t.npz"
    for cut in range(len(data)):
        bad.write_bytes(data[:cut])
        assert _load_or_clean_error(bad) == "refused", f"truncated at {cut} loaded"


@FUZZ
@given(st.data())
def test_flipped_bits_are_refused_or_harmless(good_file, tmp_path_factory, data):
    path, original = good_file
    raw = bytearray(path.read_bytes())
    for _ in range(data.draw(st.integers(1, 4))):
        pos = data.draw(st.integers(0, len(raw) - 1))
        raw[pos] ^= 1 << data.draw(st.integers(0, 7))
    bad = tmp_path_factory.mktemp("flip") / "f.npz"
    bad.write_bytes(bytes(raw))
    _load_or_clean_error(bad, original)


@FUZZ
@given(st.binary(max_size=2048))
def test_random_bytes_are_refused(tmp_path_factory, blob):
    bad = tmp_path_factory.mktemp("blob") / "b.npz"
    bad.write_bytes(blob)
    assert _load_or_clean_error(bad) == "refused"


def test_object_arrays_in_any_member_are_refused(tmp_path):
    for member in ("header", "weights", "state_w"):
        evil = tmp_path / f"{member}.npz"
        arrays = {"header": np.zeros(3, np.uint8), "weights": np.zeros((3, 4, 4))}
        arrays[member] = np.array([{"__reduce__": "os.system"}], dtype=object)
        np.savez(evil, **arrays)
        with pytest.raises(ModelFileError):
            sigmapi.load(evil)


def test_a_folder_is_not_a_model(tmp_path):
    with pytest.raises(ModelFileError, match="not a regular file"):
        sigmapi.load(tmp_path)


toml_values = st.one_of(
    st.integers(-(10**12), 10**12), st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(), st.text(max_size=8), st.lists(st.integers(-3, 20), max_size=3),
    st.lists(st.lists(st.floats(-2, 10), min_size=2, max_size=2), max_size=3),
)  # fmt: skip
keys = st.sampled_from([f.name for f in SOMConfig.__dataclass_fields__.values()] + ["bogus"])


@FUZZ
@given(st.dictionaries(keys, toml_values, max_size=4))
def test_config_dicts_build_or_raise_config_error(d):
    try:
        cfg = SOMConfig.from_dict(d)
    except ConfigError:
        return
    assert isinstance(cfg, SOMConfig)
    assert cfg.iterations >= 1 and min(cfg.map_shape) >= 1


@FUZZ
@given(st.text(max_size=300))
def test_config_files_parse_or_raise_config_error(tmp_path_factory, text):
    p = tmp_path_factory.mktemp("cfg") / "c.toml"
    p.write_text(text, encoding="utf-8")
    try:
        load_config_file(p)
    except ConfigError:
        pass


@FUZZ
@given(st.lists(st.text(max_size=30), max_size=3))
def test_set_overrides_parse_or_raise_config_error(items):
    try:
        apply_overrides(SOMConfig(), items)
    except ConfigError:
        pass


def test_config_file_that_is_binary_is_named(tmp_path):
    p = tmp_path / "c.toml"
    p.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(ConfigError, match="UTF-8"):
        load_config_file(p)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"map_shape": (15, 0)}, r"map_shape must be .* got \(15, 0\)"),
        ({"x_shape": (3, 3), "y_shape": (3,)}, "same number of dimensions"),
        ({"iterations": 0}, "iterations must be an int >= 1"),
        ({"iterations": 1.5}, "iterations must be an int"),
        ({"eps": 0.0}, r"eps values must lie in \(0, 1\]"),
        ({"eps": 2.0}, r"eps values must lie in \(0, 1\]"),
        ({"sigma": [[0.0, -1.0]]}, "sigma values must be > 0"),
        ({"sigma": [[0.5, 1.0], [0.2, 2.0]]}, "rise strictly"),
        ({"sigma": "wide"}, "sigma"),
        ({"code_width": float("nan")}, "code_width must be a finite number"),
        ({"init_scale": float("inf")}, r"init_scale must be a number in \(0, 1e\+15\]"),
        ({"init_scale": 1e308}, r"init_scale must be a number in \(0, 1e\+15\], got 1e\+308"),
        ({"init_scale": 1e39}, "float32's range"),
        ({"code_height": 1e20}, r"code_height must be a number in \(0, 1e\+07\]"),
        ({"code_width": 0.01}, r"code_width must be a finite number >= 0.1, got 0.01"),
        ({"kernel_tol": 1.0}, "kernel_tol must be"),
        ({"seed": -1}, "seed must be"),
        ({"backend": "cuda"}, "backend must be one of"),
        ({"periodic": "yes"}, "periodic must be true or false"),
    ],
)
def test_every_bad_value_is_named(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        SOMConfig(**kwargs)


def test_api_inputs_are_validated(small_1d):
    som = SigmaPiSOM(small_1d).fit(iterations=10)
    x = som.x_code.encode([[0.3]])
    with pytest.raises(ValueError, match=r"x must have shape \(B, 7\)"):
        som.winner(np.zeros((1, 8)), x)
    with pytest.raises(ValueError, match="numeric"):
        som.winner(np.array([["a"] * 7]), x)
    with pytest.raises(ValueError, match="finite"):
        som.respond(np.full((1, 7), np.inf), x)
    with pytest.raises(ValueError, match="same number of rows"):
        som.respond(np.vstack([x, x]), x)
    with pytest.raises(ConfigError, match="iterations must be an int >= 0, got -3"):
        som.partial_fit(iterations=-3)
    with pytest.raises(ValueError, match="n_test must be"):
        sigmapi.evaluate(som, n_test=1)
    with pytest.raises(ConfigError, match=r"config must be a sigmapi\.SOMConfig"):
        SigmaPiSOM({"iterations": 5})  # type: ignore[arg-type]


def test_extra_holds_only_plain_values_of_bounded_size(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("iterations = 10\n[extra]\nwhen = 1979-05-27\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"extra\.when must be a string, number, bool"):
        load_config_file(p)  # a TOML date would crash the run at its first save
    with pytest.raises(ConfigError, match="extra must be at most 65536 bytes of JSON"):
        SOMConfig(extra={"notes": "x" * 70_000})
    with pytest.raises(ConfigError, match="finite"):
        SOMConfig(extra={"v": [1.0, float("nan")]})
    ok = SOMConfig(extra={"source": "paper", "n": [1, 2.5, True], "t": {"a": "b"}})
    som = SigmaPiSOM(ok.replace(map_shape=(2,), x_shape=(2,), y_shape=(2,), iterations=5))
    back = sigmapi.load(som.fit().save(tmp_path / "m.npz"))
    assert back.config.extra == ok.extra
