"""The fuzz suite: hostile files and arguments at every loader and command (issue 17).

Each target of :mod:`footfall.cli.fuzz` gets a bounded number of Hypothesis cases
(derandomised, so CI sees the same inputs every time); any traceback, hang, memory blow-up,
garbage accepted or refusal of more than one line fails the test with the case that caused
it. ``footfall bench fuzz --minutes N`` runs the same targets for longer.
"""

import time
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from footfall.cli.fuzz import craft
from footfall.cli.fuzz.bases import make_bases
from footfall.cli.fuzz.harness import Garbage, Multiline, cli_work, guarded
from footfall.cli.fuzz.targets import TARGETS, run_case
from footfall.core.errors import FootfallError

EXAMPLES = {"map-file": 120, "model-file": 60, "store": 40, "scan-import": 120,
            "survey-import": 60, "cli": 40,
            "lying-file": 26, "concurrency": 2, "classes": 30}


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    return make_bases(tmp_path_factory.mktemp("fuzz-bases"))


def test_every_target_is_fuzzed():
    from footfall.cli.bench import FUZZ_TARGETS

    assert set(EXAMPLES) == set(TARGETS) == set(FUZZ_TARGETS)  # and each can be chosen


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_hostile_input_is_refused_in_one_line_or_accepted_valid(name, bases, tmp_path):
    target = TARGETS.get(name)

    @settings(max_examples=EXAMPLES[name], deadline=None, database=None, derandomize=True,
              suppress_health_check=list(HealthCheck))
    @given(target.cases)
    def check(case):
        outcome = run_case(target, case, bases, tmp_path / "case")
        assert not outcome.failed, f"{outcome.kind}: {outcome.detail}\ncase: {outcome.case}"

    check()


# ------------------------------------------------------------- the harness itself
def test_the_harness_reports_each_kind_of_failure():
    def raises(exc):
        def work():
            raise exc
        return work

    def warns():
        warnings.warn("overflow", RuntimeWarning)

    def sleeps():
        time.sleep(5)

    assert guarded("t", "c", lambda: None, 5).kind == "ok"
    assert guarded("t", "c", raises(FootfallError("bad value")), 5).kind == "refused"
    quoted = guarded("t", "c", raises(FootfallError("a library's\nmessage")), 5)
    assert (quoted.kind, quoted.detail) == ("refused", "a library's message")  # one line always
    assert guarded("t", "c", raises(Multiline("exit 2 with 3 lines")), 5).kind == "multiline"
    assert guarded("t", "c", raises(KeyError("x")), 5).kind == "traceback"
    assert guarded("t", "c", raises(Garbage("NaN reward")), 5).kind == "garbage"
    assert guarded("t", "c", warns, 5).kind == "multiline"
    assert guarded("t", "c", sleeps, 0.2).kind == "hang"
    assert guarded("t", "c", lambda: np.ones(1 << 40, np.uint8), 5).kind == "memory"


def test_a_command_that_accepts_what_it_must_refuse_is_garbage(tmp_path):
    out = tmp_path / "m.npz"
    ok = guarded("cli", "c", cli_work(["terrain", "make", "flat", "--seed", "1", "-o", str(out)],
                                      must_refuse=False), 30)
    assert ok.kind == "ok"
    assert guarded("cli", "c", cli_work(["terrain", "make", "flat", "--seed", "1", "-o",
                                         str(out)], must_refuse=True), 30).kind == "garbage"
    refused = guarded("cli", "c", cli_work(["terrain", "make", "nope", "--seed", "1", "-o",
                                            str(out)], must_refuse=True), 30)
    assert refused.kind == "refused" and refused.detail.startswith("footfall: error:")


def test_a_fuzzed_relative_output_lands_in_the_scratch_folder(tmp_path, monkeypatch):
    # a random output name ("T", "0") once landed in the repository's root and was committed
    scratch, home = tmp_path / "scratch", tmp_path / "home"
    scratch.mkdir()
    home.mkdir()
    monkeypatch.chdir(home)
    ok = guarded("cli", "c", cli_work(["terrain", "make", "flat", "--seed", "1", "-o", "T.npz"],
                                      must_refuse=False, cwd=scratch), 30)
    assert ok.kind == "ok"
    assert (scratch / "T.npz").is_file() and list(home.iterdir()) == []


def test_crafted_archives_are_what_they_claim(tmp_path):
    """The crafted inputs really are hostile: a pickle member would run, a huge member claims
    terabytes, an encrypted archive is flagged -- so refusing them is a real test."""
    import io
    import pickle
    import zipfile

    marker = tmp_path / "ran"
    member = craft.pickle_member(str(marker))
    with pytest.raises(ValueError):
        np.load(io.BytesIO(member), allow_pickle=False)
    assert member.endswith(craft.pickle_payload(str(marker)))
    pickle.loads(craft.pickle_payload(str(marker))).close()  # noqa: S301 - the payload is live
    assert marker.exists()
    header = np.lib.format.read_array_header_1_0(
        io.BytesIO(craft.huge_member((1 << 20, 1 << 18))[8:]))
    assert np.prod(header[0]) * 8 >= 1 << 41
    data = craft.patch_zip(craft.write_npz({"a": np.zeros(3)}), "encrypt", 0)
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        assert zf.infolist()[0].flag_bits & 1


# Cases the long run (footfall bench fuzz) found, kept as they were drawn.
FOUND = [
    # a flipped byte in the schema's text: reading sqlite_master raised UnicodeDecodeError
    ("store", ([("bytes", "flip", 3079), ("drop", "meta"), ("ddl", "table")], "collect")),
    # float16 heights with a nodata beyond float16's range: NumPy's overflow warning
    ("scan-import", (".npy", [("line", 999999, "format binary_little_endian 1.0"),
                              ("array", ("float16", 1))], 8246631289051090.0, 0.005,
                     8246631289051090.0)),
    # a candidate count stored as text: the store's summary after a write raised ValueError
    ("store", ([("cell", "demonstrations", 1016, 244708, "LF")], "collect")),
    # NumPy's three-line message on a huge .npy header, quoted in a FootfallError
    ("scan-import", (".npy", [("array", ("nan", 9)), ("bytes", "delete", 9),
                              ("bytes", "flip", 426)], 0.005, 0.005, None)),
    # an input name with an unpaired surrogate: comparing it with the output raised
    # UnicodeEncodeError
    ("cli", (3, [(57, False, 79, "\x1bf\x8e\xb2\xb8\udc50")])),
    # a LAZ chunk table counting 1.7 billion chunks: the LAZ decoder allocated 26 GB for them
    # and the process died
    ("survey-import", (".laz", [("zero_run", 1081530686), ("delete", 2084654369)], {})),
    # a LAS header counting 2.2 billion variable-length records: laspy read past the end of
    # the file for hours
    ("survey-import", (".laz", [("delete", 793289931), ("flip", 1186724181),
                                ("truncate", 1275442510)], {})),
    # a GeoTIFF cut short of its geotransform: rasterio's NotGeoreferencedWarning beside the line
    ("survey-import", (".tif", [("truncate", 170478)], {})),
    # a grid_map layer whose damaged floats hold a signalling NaN: NumPy's cast warning
    ("survey-import", (".db3", [("insert", 41090)], {})),
    # a run step whose slip is 6.6e16 m: accepted by `store check` as a distance
    ("store", ([("cell", "run_steps", 2509, 318420, 6.590407141598128e+16)], "check")),
    # an input map named by an unpaired surrogate: reading its size raised UnicodeEncodeError
    ("cli", (2, [(30, False, 30, "\udb06")])),
    # a flipped byte that SQLite's integrity check quotes: its message was not UTF-8
    ("store", ([("cell", "run_steps", 1780, 2971, -6.901954443138086e-142),
                ("bytes", "flip", 2147483647)], "check")),
    # a model whose robot has its hips 0.61 m from the body origin: NaN rewards
    ("model-file", [("zip", "sizes", 708), ("meta", 100760, "replace", 0.61)]),
]


@pytest.mark.parametrize("name, case", FOUND, ids=[f"{n}-{i}" for i, (n, _) in enumerate(FOUND)])
def test_cases_the_long_run_found_stay_fixed(name, case, bases, tmp_path):
    outcome = run_case(TARGETS.get(name), case, bases, tmp_path / "case")
    assert not outcome.failed, f"{outcome.kind}: {outcome.detail}"


@pytest.mark.parametrize("case", [("correct",), ("folder",)], ids=["corrections", "folder"])
def test_two_commands_into_one_store_or_folder_at_once(case, bases, tmp_path):
    """Every race of the concurrency target beyond walk-many's, once: two corrections into one
    output store (each label once), two folder-owning commands into one folder (one walks,
    the other is refused in one line or walks after it; each run once)."""
    outcome = run_case(TARGETS.get("concurrency"), case, bases, tmp_path / "case")
    assert outcome.kind == "ok", f"{outcome.kind}: {outcome.detail}"
