"""`artic corpus` on a LocalCluster of 2 workers: bad and unreachable items recorded while the rest finish, an
interrupted run resumed without redoing what finished, a killed worker's item spoken elsewhere, a finished
corpus left alone; the list's and the index's rules."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import ROOT, praat_f0, run_cli
from artic_cli.corpus.index import finished, read_index
from artic_cli.corpus.listing import read_listing
from artic_cli.errors import ArticError
from artic_cli.io.wav import read_wav
from artic_cli.stages.corpus import Setup, run_corpus

CONFIG = ROOT / "configs" / "ci_thin.yaml"  # thin maps: built in seconds
# ten items: eight that speak, one with a character that is not romaji, one whose /o/ the test inventory puts
# out of reach (F1 150 Hz, F2 3000 Hz)
LIST = ("w01\ta\nw02\ti\nw03\tu\nw04\te\nw05\taka\nw06\tpapa\nbad\tax\nw07\tgaga\nunr\tao\nw08\tama\t1.5\n")


@pytest.fixture(scope="module")
def corpus_setup(tmp_path_factory):
    from artic_cli.stages.acoustic_map import acoustic_map
    from artic_cli.stages.dynamic import build_dynamic_map
    from artic_cli.stages.epmap import build_ep_maps
    from artic_cli.stages.mesh import build_mesh

    tmp = tmp_path_factory.mktemp("corpus")
    build_mesh(CONFIG, tmp / "mesh.h5")
    build_ep_maps(tmp / "mesh.h5", CONFIG, tmp / "maps.h5", jobs=2, cache=tmp / "cache")
    acoustic_map(tmp / "maps.h5", tmp / "mesh.h5", CONFIG, tmp / "am.h5", jobs=2)
    build_dynamic_map(tmp / "maps.h5", tmp / "dynamic.h5")
    inv = (ROOT / "configs" / "phonemes" / "japanese.yaml").read_text()
    assert inv.count("formants_hz: [520, 997]") == 1
    (tmp / "inventory.yaml").write_text(inv.replace("formants_hz: [520, 997]", "formants_hz: [150, 3000]"))
    (tmp / "list.tsv").write_text(LIST)
    setup = Setup(maps=str(tmp / "maps.h5"), mesh=str(tmp / "mesh.h5"), acoustic_maps=str(tmp / "am.h5"),
                  dynamic=str(tmp / "dynamic.h5"), config=str(CONFIG), inventory=str(tmp / "inventory.yaml"),
                  solutions=str(tmp / "solutions"))
    return tmp, setup


@pytest.fixture(scope="module")
def spoken(corpus_setup):
    tmp, setup = corpus_setup
    said = []
    res = run_corpus(tmp / "list.tsv", tmp / "one", setup, jobs=2, say=said.append)
    return tmp / "one", res, said


def _rows(folder):
    return [json.loads(line) for line in (folder / "index.jsonl").read_text().splitlines()]


def test_a_bad_and_an_unreachable_item_are_recorded_while_the_other_eight_finish(spoken):
    out, res, said = spoken
    rows = {r["id"]: r for r in _rows(out)}
    assert list(rows) == [r.id for r in read_listing(out.parent / "list.tsv")]  # the list's order
    ok = [r for r in rows.values() if r["status"] == "ok"]
    assert len(ok) == 8 and res.spoken == 8 and res.kept == 0
    assert rows["bad"]["status"] == "failed" and rows["bad"]["exit_code"] == 2
    assert "'x' at position 2" in rows["bad"]["error"]
    assert rows["unr"]["status"] == "unreachable" and rows["unr"]["exit_code"] == 3
    assert "F1 150 Hz, F2 3000 Hz are not reachable" in rows["unr"]["error"]
    assert any(m.startswith("unr: unreachable") for m in said) and any(m.startswith("bad: failed") for m in said)
    assert not list((out / "items").glob("bad.*")) and not list((out / "items").glob("unr.*"))
    for r in ok:
        for key in ("wav", "textgrid", "h5", "ema"):
            assert (out / r[key]).is_file(), r
        assert r["sample_rate_hz"] == 44100 and r["duration_s"] > 0.1 and r["wall_s"] > 0
    assert rows["w05"]["phones"] == "a k a" and rows["w08"]["rate"] == 1.5
    assert rows["w08"]["duration_s"] < rows["w05"]["duration_s"]  # ama at 1.5 times the rate of aka
    assert not list(out.rglob("*.tmp*"))
    # the CSV twin holds the same rows
    import csv

    with open(out / "index.csv") as fh:
        table = list(csv.DictReader(fh))
    assert [t["id"] for t in table] == list(rows) and table[4]["wav_sha256"] == rows["w05"]["wav_sha256"]


def test_the_ema_table_and_the_textgrid_follow_the_simulation(spoken):
    import h5py

    out, _, _ = spoken
    head, *lines = (out / "items" / "w05.ema.csv").read_text().splitlines()
    assert head.split(",") == ["time_s", "tip_x_cm", "tip_y_cm", "blade_x_cm", "blade_y_cm", "dorsum_x_cm",
                               "dorsum_y_cm", "jaw_x_cm", "jaw_y_cm", "lip_area_cm2", "lip_length_cm"]
    table = np.array([[float(v) for v in ln.split(",")] for ln in lines])
    with h5py.File(out / "items" / "w05.h5") as f:
        t, dorsum = f["time"][()], f["control_points/dorsum"][()]
    assert len(table) == len(t) and np.allclose(table[:, 0], t, atol=1e-5)
    assert np.allclose(table[:, 5:7], dorsum[:, :2], atol=1e-4)
    tip, blade, dors = table[0, 1], table[0, 3], table[0, 5]
    assert tip > blade > dors  # tip in front of the blade in front of the dorsum (x anterior)
    assert np.ptp(table[:, 6]) > 0.1  # the dorsum rises to close for /k/ and comes down
    from praatio import textgrid

    tg = textgrid.openTextgrid(str(out / "items" / "w05.TextGrid"), includeEmptyIntervals=False)
    assert [e.label for e in tg.getTier("phones").entries] == ["a", "k", "a"]


def test_the_dataset_card_says_what_made_the_corpus_and_how_to_load_it(spoken, corpus_setup):
    out, _, _ = spoken
    card = (out / "README.md").read_text()
    assert "10 items: 8 spoken" in card and "1\nunreachable, 1 failed" in card
    from artic_cli.io.store import stored_content_hash

    assert stored_content_hash(corpus_setup[1].maps) in card and "pd.read_csv" in card and "CC BY 4.0" in card
    assert "`unr` (unreachable)" in card


def test_a_rerun_of_a_finished_corpus_does_nothing_and_says_so(spoken, corpus_setup):
    out, _, _ = spoken
    tmp, setup = corpus_setup
    before = {p: p.stat().st_mtime_ns for p in (out / "items").iterdir()}
    said = []
    res = run_corpus(tmp / "list.tsv", out, setup, jobs=2, say=said.append)
    assert res.spoken == 0 and res.kept == 10 and said == [f"nothing to do: all 10 items of {tmp / 'list.tsv'} are "
                                                             f"done in {out}"]
    assert {p: p.stat().st_mtime_ns for p in (out / "items").iterdir()} == before
    # a changed file is not done: that item alone is spoken again
    wav = out / "items" / "w02.wav"
    wav.write_bytes(wav.read_bytes()[:-2] + b"\x00\x01")
    res = run_corpus(tmp / "list.tsv", out, setup, jobs=1)
    assert res.spoken == 1 and res.kept == 9


def test_an_interrupted_corpus_goes_on_where_it_stopped_and_matches_an_uninterrupted_one(spoken, corpus_setup):
    tmp, setup = corpus_setup
    out = tmp / "two"
    args = [sys.executable, "-m", "artic_cli.cli.main", "corpus", str(tmp / "list.tsv"), "--out", str(out),
            "--jobs", "2", "--maps", setup.maps, "--mesh", setup.mesh, "--acoustic-maps", setup.acoustic_maps,
            "--dynamic", setup.dynamic, "--config", setup.config, "--inventory", setup.inventory,
            "--solutions", setup.solutions]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(read_index(out)) < 3:
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "run the same command again to go on" in err, err[-2000:]
    done = read_index(out)
    assert 3 <= len(done) < 10
    mtimes = {p: p.stat().st_mtime_ns for r in done.values() if r["status"] == "ok"
              for p in (out / r["wav"], out / r["h5"])}
    res = run_corpus(tmp / "list.tsv", out, setup, jobs=2)
    # the rerun keeps every finished row and speaks at most the sounding items not yet finished
    assert res.kept == len(done) and res.spoken <= 8 - sum(r["status"] == "ok" for r in done.values())
    assert {p: p.stat().st_mtime_ns for p in mtimes} == mtimes  # finished items untouched
    assert not list(out.rglob("*.tmp*"))
    one = spoken[0]
    strip = lambda rows: [{k: v for k, v in r.items() if k != "wall_s"} for r in rows]  # noqa: E731
    assert strip(_rows(out)) == strip(_rows(one))  # the same list: the same index and hashes


def _workers() -> list:
    import psutil

    return [p for p in psutil.Process().children(recursive=True)
            if "spawn_main" in " ".join(p.cmdline()) and "resource_tracker" not in " ".join(p.cmdline())]


def test_a_worker_killed_mid_run_has_its_item_spoken_elsewhere(corpus_setup):
    tmp, setup = corpus_setup
    (tmp / "six.tsv").write_text("".join(f"k{k}\t{t}\n" for k, t in enumerate(["aka", "papa", "gaga", "ama",
                                                                                 "iki", "aga"])))
    killed = []

    def kill_one(done, total, failed):
        if done == 1 and not killed:
            workers = _workers()
            assert len(workers) == 2, workers
            workers[0].kill()
            killed.append(workers[0].pid)

    res = run_corpus(tmp / "six.tsv", tmp / "killed", setup, jobs=2, progress=kill_one)
    assert killed and not os.path.exists(f"/proc/{killed[0]}")
    assert [r["status"] for r in res.rows] == ["ok"] * 6, [r.get("error") for r in res.rows]


def test_a_corpus_runs_on_an_existing_cluster_given_its_scheduler_address(corpus_setup, spoken):
    from dask.distributed import LocalCluster

    tmp, setup = corpus_setup
    (tmp / "two.tsv").write_text("x1\taka\nx2\tpapa\n")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        res = run_corpus(tmp / "two.tsv", tmp / "remote", setup, scheduler=cluster.scheduler_address)
        pids = {p.pid for p in _workers()}
    assert [r["status"] for r in res.rows] == ["ok", "ok"] and set(res.peak_mb) == pids  # spoken on its worker
    one = {r["id"]: r for r in _rows(spoken[0])}
    assert res.rows[0]["wav_sha256"] == one["w05"]["wav_sha256"]  # the same text, the same sound


def test_the_list_s_form_is_checked_on_load_with_one_line(tmp_path):
    cases = {"dup.tsv": ("a\taka\na\tiki\n", "id 'a' is already used on line 1"),
             "name.tsv": ("../x\taka\n", "cannot be a file name"),
             "rate.tsv": ("a\taka\tfast\n", "rate 'fast' is not a number"),
             "cols.tsv": ("a\taka\t1\t0\tc.yaml\textra\n", "give at most 5"),
             "empty.tsv": ("# nothing\n\n", "holds no items"),
             "head.csv": ("name,text\na,aka\n", "must name 'id' and 'text'"),
             "conf.tsv": ("a\taka\t1\t\tnone.yaml\n", "config none.yaml not found")}
    for name, (text, says) in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(ArticError, match=says):
            read_listing(tmp_path / name)
    (tmp_path / "ok.csv").write_text('id,text,accent\nh,"hashi",1\nb,"hashi",0\n')
    items = read_listing(tmp_path / "ok.csv")
    assert [(i.id, i.text, i.rate, i.accent) for i in items] == [("h", "hashi", 1.0, 1), ("b", "hashi", 1.0, 0)]


def test_an_accent_column_places_the_fall(tmp_path):
    from artic_cli.speech.inventory import load_inventory
    from artic_cli.speech.text import utterance_of_text

    inv = load_inventory()
    marked, given = utterance_of_text("ha'shi", inv), utterance_of_text("hashi", inv, accent=1)
    assert marked.f0_hz == given.f0_hz and utterance_of_text("hashi", inv, accent=0).f0_hz != given.f0_hz
    for text, accent, says in (("ha'shi", 1, "without an accent mark"), ("hashi", 3, "has 2 morae"),
                               ("ha shi", 1, "for one word")):
        with pytest.raises(ArticError, match=says):
            utterance_of_text(text, inv, accent=accent)


def test_an_index_row_is_done_only_with_its_recipe_and_its_files(tmp_path):
    row = {"id": "a", "status": "failed", "exit_code": 2, "recipe_sha256": "r"}
    assert finished(tmp_path, row, "r") and not finished(tmp_path, row, "other")
    assert not finished(tmp_path, dict(row, exit_code=1), "r")  # a crash is tried again
    ok = {"id": "a", "status": "ok", "exit_code": 0, "recipe_sha256": "r", "wav": "a.wav", "textgrid": "a.TextGrid",
          "ema": "a.ema.csv", "h5": "a.h5"}
    assert not finished(tmp_path, ok, "r")  # its files are gone


@pytest.mark.parametrize("args, says", [(["none.tsv"], "corpus list not found"),
                                        (["LIST", "--jobs", "0"], "--jobs"),
                                        (["LIST", "--maps", "none.h5"], "none.h5 is missing or unreadable")])
def test_bad_corpus_input_is_one_line_and_exit_2(tmp_path, monkeypatch, args, says):
    (tmp_path / "LIST").write_text("a\taka\n")
    monkeypatch.chdir(tmp_path)
    res = run_cli("corpus", *args, "--out", tmp_path / "out")
    assert res.exit_code == 2 and says in res.output and len(res.output.strip().splitlines()) == 1, res.output
    assert not (tmp_path / "out").exists()


def test_a_worker_keeps_what_it_loaded_until_the_file_changes(tmp_path):
    from artic_cli.stages import loaded

    f = tmp_path / "maps.h5"
    f.write_bytes(b"one")
    made = []
    make = lambda: made.append(1) or object()  # noqa: E731
    a = loaded.once("test", make, (f, None))
    assert loaded.once("test", make, (f, None)) is a and len(made) == 1  # loaded once
    f.write_bytes(b"other content")
    assert loaded.once("test", make, (f, None)) is not a and len(made) == 2  # the file changed: loaded again
    for k in range(loaded.KEEP + 1):
        loaded.once("test", make, (tmp_path / f"m{k}", None))
    assert len(loaded._kept["test"]) == loaded.KEEP  # the oldest dropped
    loaded.forget()


def test_a_word_at_another_pitch_is_not_timed_again_and_moves_the_same(corpus_setup):
    """The timing's leads and presses are kept beside the solutions (stages/speak.py, ``timed_once``): the same
    word at another pitch range and under another name reuses them, moves exactly as before and sounds at its
    own pitch."""
    from artic_cli.speech.inventory import load_inventory
    from artic_cli.speech.text import utterance_of_text
    from artic_cli.stages import speak as speak_stage

    tmp, setup = corpus_setup
    inv = load_inventory(setup.inventory)
    said = {}
    for name, f0 in (("low", (90.0, 120.0)), ("high", (140.0, 190.0))):
        said[name] = []
        u = utterance_of_text("aka", inv, name=name, f0_range_hz=f0)
        speak_stage.speak(u, tmp / "pitch" / f"{name}.wav", setup.maps, setup.mesh, setup.acoustic_maps,
                          setup.config, tmp / "pitch" / "solutions", dynamic=setup.dynamic,
                          inventory=setup.inventory, say=said[name].append)
    timing = {k: [m for m in v if m.startswith("timing:")] for k, v in said.items()}
    assert "round(s)" in timing["low"][0] and "as found before" in timing["high"][0], timing
    assert timing["low"][0].split(";", 1)[1] == timing["high"][0].split(";", 1)[1]  # the same leads and presses
    low, high = (speak_stage.read(tmp / "pitch" / f"{n}.h5") for n in ("low", "high"))
    for name in low.control_points:
        assert np.array_equal(low.control_points[name], high.control_points[name])
    assert list(low.leads_ms) == list(high.leads_ms) and list(low.press) == list(high.press)
    assert len(low.drive) == len(low.press) and list(low.drive) == list(high.drive)  # the drives kept too
    assert np.array_equal(low.commanded_n, high.commanded_n)  # and the forces, its vowels' aims among them
    y, rate = read_wav(tmp / "pitch" / "low.wav")
    times = np.linspace(0.03, len(y) / rate - 0.03, 25)
    f0 = {n: float(np.nanmedian(praat_f0(tmp / "pitch" / f"{n}.wav", times))) for n in ("low", "high")}
    assert 85 <= f0["low"] <= 125 and 135 <= f0["high"] <= 195, f0


def _word_phones(spoken, item):
    from artic_cli.speech.inventory import load_inventory
    from artic_cli.speech.textgrid import read_phones
    from artic_cli.stages import speak as speak_stage

    out, _, _ = spoken
    wav = out / "items" / f"{item}.wav"
    inv = load_inventory()
    y, rate = read_wav(wav)
    return wav, speak_stage.read(wav.with_suffix(".h5")), y, rate, read_phones(wav.with_suffix(".TextGrid")), inv


def _middle(a, b):
    return a + 0.25 * (b - a), b - 0.25 * (b - a)


def _class_margin(f, means) -> float:
    """How much nearer (Bark) formants ``f`` lie to their nearest vowel mean than to the next."""
    from artic_cli.speech.vowel_class import bark_distance

    d = sorted(bark_distance(f, m) for m in means.values())
    return d[1] - d[0]


def _praat_voiced(wav, a, b) -> float:
    return float(np.mean(np.isfinite(praat_f0(wav, np.arange(a + 0.0025, b, 0.005)))))


def test_praat_hears_the_spoken_words_phones_as_the_judge_measures_them(spoken):
    """Issue 46's judge (speech/judge.py, speech/landmarks.py) on words spoken from text (aka, papa, gaga, ama
    on the CI speaker), against Praat on the same WAVs over the TextGrid's intervals: a consonant between vowels
    has its level against their middle halves within 2 dB of Praat's (where Praat hears more than 50 dB below
    the vowels: a closure with no voice is digital silence, where Praat's floor decides), and a vowel Praat
    hears voiced through its middle half is heard as intended by both or by neither (Praat's Burg formants),
    as the same vowel where each lies at least 0.5 Bark nearer its nearest mean than the next (gaga's first
    /a/, aimed in context on the CI speaker, sits on the /e/-/u/ tie: ours 451 / 1643 Hz, 0.37 Bark nearer
    /e/, Praat's 423 / 1608 Hz, 0.11 nearer /u/), F1 and F2 within 10 %."""
    from artic_cli.speech.judge import phone_results
    from artic_cli.speech.landmarks import consonants
    from artic_cli.speech.vowel_class import nearest_vowel

    from conftest import praat_formants_near, praat_level_db

    checked = {"consonant": 0, "vowel": 0}
    for item in ("w05", "w06", "w07", "w08"):
        wav, rec, y, rate, iv, inv = _word_phones(spoken, item)
        manners = {k: p.manner for k, p in inv.phonemes.items()}
        means = {v: tuple(p.formants_hz[:2]) for v, p in inv.phonemes.items() if p.manner == "vowel"}
        vowels = [(a, b) for a, b, s in iv if manners.get(s) == "vowel"]
        ref = float(np.mean([praat_level_db(wav, *_middle(a, b)) for a, b in vowels]))
        for m in consonants(y, rate, iv, manners):
            t0, t1 = m["start_s"], m["start_s"] + m["duration_ms"] / 1e3
            praat = praat_level_db(wav, t0, t1) - ref
            if t0 > 0 and praat > -50:
                assert abs(m["level_db"] - praat) <= 2.0, (item, m["symbol"], m["level_db"], praat)
                checked["consonant"] += 1
        for r in phone_results(y, rate, iv, rec.time_s, rec.formants_hz, inv):
            a, b = _middle(r["start_s"], r["end_s"])
            if r["kind"] != "vowel" or _praat_voiced(wav, a, b) < 0.9:
                continue
            inside = (rec.time_s >= a) & (rec.time_s <= b)
            f = [float(np.nanmedian(rec.formants_hz[inside, k])) for k in (0, 1)]
            heard, _ = praat_formants_near(wav, np.linspace(a, b, 7), f)
            ours, theirs = nearest_vowel(*f, means), nearest_vowel(heard[0], heard[1], means)
            assert (ours == r["label"]) == (theirs == r["label"]), (item, r, heard, f)  # the judge's verdict
            if min(_class_margin(f, means), _class_margin(heard, means)) >= 0.5:  # clear of a tie: the same vowel
                assert ours == theirs, (item, r, heard, f)
            assert abs(heard[0] / f[0] - 1) <= 0.10 and abs(heard[1] / f[1] - 1) <= 0.10, (item, r, heard, f)
            checked["vowel"] += 1
    assert checked["consonant"] >= 2 and checked["vowel"] >= 3, checked


@pytest.mark.xfail(strict=True, reason="ours calls /ama/'s 43-ms /m/ (rate 1.5) voiced in all of it, Praat in 78 %: "
                                       "its path finder jumps an octave in the murmur (272-306 Hz after 118 Hz) and "
                                       "calls the frames at each jump unvoiced (the lab's /ama/ agrees within 0.15)")
def test_praat_hears_a_word_s_nasal_voiced_as_the_judge_does(spoken):
    from artic_cli.speech.landmarks import consonants

    wav, rec, y, rate, iv, inv = _word_phones(spoken, "w08")
    m, = [m for m in consonants(y, rate, iv, {k: p.manner for k, p in inv.phonemes.items()}) if m["symbol"] == "m"]
    t0, t1 = m["start_s"], m["start_s"] + m["duration_ms"] / 1e3
    assert abs(m["voiced_share"] - _praat_voiced(wav, t0, t1)) <= 0.15
