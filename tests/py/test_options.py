"""The protocols' settings as option objects (trueaniso/options.py): each value checked for its type
and range once, when the object is made, before any work (reach_state(feed_forward="no") ran with
the feed-forward on: bool("no") is True); the old keyword calls still work; and a study's
fingerprint made from the objects is the one the keywords made (a study of the old code continues)."""
import json
import math
import os

import pytest
from conftest import REPO

from trueaniso import specimen_file, study, triaxial
from trueaniso.options import PathOptions, ProbeOptions, ServoOptions
from trueaniso.refusal import InputError

SPECIMEN = os.path.join(REPO, "tests", "data", "spheres-150-s4.npz")


@pytest.fixture(scope="module")
def scene():
    return specimen_file.load(SPECIMEN)[0]


@pytest.mark.parametrize("keywords,words", [
    (dict(feed_forward="no"), "feed_forward must be True or False, not 'no'"),
    (dict(feed_forward=1), "feed_forward must be True or False"),
    (dict(control_shear="yes"), "control_shear must be True or False"),
    (dict(path_rate="20"), "path_rate must be a number"),
    (dict(path_rate=float("nan")), "path_rate must be a finite number (or inf)"),
    (dict(path_rate=-1.0), "path_rate must be in (0"),
    (dict(max_steps=1e6), "max_steps must be an integer"),
    (dict(max_steps=True), "max_steps must be an integer"),
    (dict(friction=0.0), "friction must be in (0"),
    (dict(damping=1.0), "damping must be in [0, 1)"),
    (dict(shear=(0.0, 1.0)), "shear must be three shear stresses"),
    (dict(time_step="fast"), "time_step must be one of smallest-inertia, per-axis"),
    (dict(gain=2.0), "gain must be in (0, 1]"),
])
def test_reach_state_refuses_a_wrong_type_before_any_step(scene, keywords, words):
    s = scene.copy()
    step = s.step
    with pytest.raises(InputError) as info:
        triaxial.reach_state(s, 0.5, 140e3, **keywords)
    assert words in str(info.value) and str(info.value).startswith("reach_state: ")
    assert s.step == step


@pytest.mark.parametrize("keywords,words", [
    (dict(restrain_rotations="no"), "restrain_rotations must be True or False"),
    (dict(skip_detection=0), "skip_detection must be True or False"),
    (dict(settle_steps=-1), "settle_steps must be an integer >= 0"),
    (dict(relative_tolerance="2e-3"), "relative_tolerance must be a number"),
    (dict(sides="both"), "sides must be one of auto, one, two, not 'both'"),
    (dict(sides=2), "sides must be one of auto, one, two, not 2"),
])
def test_probe_refuses_a_wrong_type_before_any_step(scene, keywords, words):
    s = scene.copy()
    with pytest.raises(InputError, match=words.replace("(", r"\(").replace("[", r"\[")):
        triaxial.probe(s, [100e3] * 3, "z", **keywords)
    assert s.step == scene.step


def test_an_unknown_setting_is_refused_as_python_refuses_a_keyword(scene):
    with pytest.raises(TypeError, match="reach_state\\(\\) got an unexpected keyword argument 'feedforward'"):
        triaxial.reach_state(scene.copy(), 0.5, 140e3, feedforward=True)
    with pytest.raises(TypeError, match="probe\\(\\) got an unexpected keyword argument 'rotations'"):
        triaxial.probe(scene.copy(), [100e3] * 3, "z", rotations="free")
    with pytest.raises(TypeError, match="expected ServoOptions, not dict"):
        triaxial.reach_state(scene.copy(), 0.5, 140e3, servo=dict(path_rate=20.0))


def test_objects_and_keywords_are_one_setting():
    o = ServoOptions(path_rate=20.0, feed_forward=True)
    assert ServoOptions.of(o, dict(friction=0.3)) == ServoOptions(path_rate=20.0, feed_forward=True, friction=0.3)
    assert ServoOptions(path_rate=math.inf).path_rate == math.inf  # the whole load at once
    assert ServoOptions(max_steps=10).max_steps == 10 and ServoOptions(tolerance=100).tolerance == 100.0
    assert PathOptions(probes=(2, 0, "zy")).probes == ("z", "x", "yz")
    with pytest.raises(InputError, match="given once"):
        PathOptions(probes=("z", "z"))
    with pytest.raises(InputError, match="unknown path"):
        PathOptions(path="walls")


def test_a_committed_study_s_fingerprint_is_made_again():
    """docs/data/b1-clump2-4000-s1 was run by the keywords (per-axis states, rotations restrained),
    its probes at smallest-inertia, which it does not record (a study that records no rule was made
    with it), and one-sided, which it does not record either (the probes were one-sided before the
    sides were recorded): its recorded state and probe settings, with that rule and those sides,
    are the objects' fingerprint of the same options, the sides resolved on its specimen (rotations
    restrained: one-sided, also under the default "auto")."""
    from trueaniso import study_dir
    directory = os.path.join(REPO, "docs", "data", "b1-clump2-4000-s1")
    assert study_dir.time_step_rules_of(directory) == ("per-axis", "smallest-inertia")
    with open(os.path.join(directory, "metadata.json")) as f:
        fp = study_dir.with_unrecorded_rules(json.load(f)["fingerprint"])
    servo = ServoOptions(time_step="per-axis")
    probe = ProbeOptions(restrain_rotations=True, time_step="smallest-inertia")
    assert dict(damping=servo.damping, **servo.fingerprint()) == fp["state"]
    assert probe.fingerprint() == fp["probe"] and fp["probe"]["sides"] == "one"
    meta = specimen_file.read(SPECIMEN)[1]
    old = study.fingerprint(meta, "sphere", 1e-6, True, False, 0.4, dict(time_step="per-axis"),
                            dict(time_step="smallest-inertia"))
    new = study.study_fingerprint(meta, "sphere", PathOptions(), servo, probe)
    assert old == new and old["state"] == fp["state"] and old["probe"] == fp["probe"]
    clumps = study.study_fingerprint(meta, "clump2", PathOptions(), servo, ProbeOptions())["probe"]
    # "auto": two sides on clumps free to rotate, and their settle steps
    assert (clumps["sides"], clumps["settle_steps"], new["probe"]["settle_steps"]) == ("two", 300, 100)
    assert ProbeOptions(sides="two").fingerprint() == ProbeOptions().fingerprint(clumps=True)
    # the whole load at once is recorded as text (metadata.json stays standard JSON)
    assert study.fingerprint(meta, "sphere", 1e-6, False, False, 0.4, dict(path_rate=math.inf))["state"]["path_rate"] \
        == "inf"


def test_other_flags_of_the_api_are_flags(scene, tmp_path):
    """static_stiffness(rotations='no') solved with rotations free; run_states(wait='no') waited."""
    from trueaniso import statics
    with pytest.raises(InputError, match="static_stiffness: rotations must be True or False, not 'no'"):
        statics.static_stiffness(scene.copy(), rotations="no")
    with pytest.raises(InputError, match="run_states: wait must be True or False"):
        study.run_states(SPECIMEN, [(1, 0.0, 100e3)], str(tmp_path / "out"), wait="no")
    assert not (tmp_path / "out").exists()


def test_the_analysis_flags_are_flags(tmp_path):
    """report.build(statics='no') would solve Table B1's statics; read_metadata(required='no') and
    validate.problem(required='no') would require."""
    from trueaniso import validate
    from trueaniso.analysis import report, results
    study_dir = os.path.join(REPO, "docs", "data", "spheres-4000-s1")
    for flagged in ("statics", "b1_other_material"):
        with pytest.raises(InputError, match="report.build: %s must be True or False, not 'no'" % flagged):
            report.build(study_dir, out=str(tmp_path / "r"), log=lambda line: None, **{flagged: "no"})
    assert not (tmp_path / "r").exists()
    with pytest.raises(InputError, match="read_metadata: required must be True or False, not 0"):
        results.read_metadata(study_dir, required=0)
    with pytest.raises(InputError, match="validate.problem: required must be True or False"):
        validate.problem({}, "statics_record", required="no")
