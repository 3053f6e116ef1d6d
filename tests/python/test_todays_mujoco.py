"""A compiled mujoco.MjModel of today's MuJoCo (PyPI) through ModelBuilder.add_mujoco_model and novaphy.from_mujoco:
the same model add_mjcf builds from the file (MuJoCo 2.2.2's compile), bit for bit, and the same contact-free
dynamics as that MuJoCo's own. Skipped where PyPI's mujoco is not installed (tools/setup.sh installs it into
build/venv; docs/python.md)."""

import os
import warnings

import numpy as np
import pytest

import novaphy

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh puts it in build/venv)"
)

from mujoco_checks import by_file, largest_dynamics_difference, quiet, random_state, run  # noqa: E402

MODELS = os.path.join(os.path.dirname(__file__), "models")
SCENES = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "scenes")
FILES = [
    os.path.join(SCENES, "quadruped.xml"),
    os.path.join(MODELS, "arm.xml"),
    os.path.join(MODELS, "hand.xml"),
    os.path.join(MODELS, "gripper.xml"),
]


@pytest.mark.parametrize("precision", [novaphy.Precision.Float64, novaphy.Precision.Float32])
@pytest.mark.parametrize("path", FILES, ids=os.path.basename)
def test_from_mujoco_steps_bit_identically_to_add_mjcf(path, precision):
    m = mujoco.MjModel.from_xml_path(path)
    imported = quiet(novaphy.from_mujoco, m, 3, precision)
    read = by_file(path, 3, precision)
    q_a, qd_a = run(imported, 300, m.opt.timestep)
    q_b, qd_b = run(read, 300, m.opt.timestep)
    assert np.all(np.isfinite(q_a))
    assert q_a.tobytes() == q_b.tobytes()
    assert qd_a.tobytes() == qd_b.tobytes()


@pytest.mark.parametrize("path", FILES + ["/usr/share/mujoco/model/humanoid/humanoid.xml"], ids=os.path.basename)
def test_contact_free_dynamics_match_todays_mujoco(path):
    if not os.path.exists(path):
        pytest.skip(f"{path} is not installed (libmujoco-samples)")
    assert largest_dynamics_difference(mujoco.MjModel.from_xml_path(path)) < 1e-9


def test_state_maps_go_both_ways():
    m = mujoco.MjModel.from_xml_path(os.path.join(SCENES, "quadruped.xml"))
    d = mujoco.MjData(m)
    random_state(m, d, np.random.default_rng(3))
    imported = quiet(novaphy.ModelBuilder().add_mujoco_model, m)
    q = imported.to_joint_q(d.qpos)
    qd = imported.to_joint_qd(d.qpos, d.qvel)
    assert q[:3].tolist() == d.qpos[:3].tolist()  # the base position; then [x y z w] for MuJoCo's [w x y z]
    assert np.allclose(q[3:7], [d.qpos[4], d.qpos[5], d.qpos[6], d.qpos[3]], rtol=0, atol=1e-15)
    assert np.allclose(imported.to_qpos(q), d.qpos, rtol=0, atol=1e-15)
    assert np.allclose(imported.to_qvel(d.qpos, qd), d.qvel, rtol=0, atol=1e-14)
    with pytest.raises(ValueError, match="qpos has 3 entries; the imported model has 19"):
        imported.to_joint_q(np.zeros(3))


def test_what_is_not_an_mjmodel_is_named():
    with pytest.raises(ValueError, match="has no field 'nq'"):
        novaphy.ModelBuilder().add_mujoco_model(object())


def test_an_unmodelled_field_of_todays_mujoco_is_reported():
    m = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body gravcomp="1"><joint name="j" type="hinge" actuatorgravcomp="true" '
        'actuatorfrcrange="-1 1"/><geom size="0.1"/></body></worldbody></mujoco>'
    )
    with pytest.warns(UserWarning, match="joint 'j': actuatorgravcomp under an actuatorfrcrange"):
        novaphy.ModelBuilder().add_mujoco_model(m)


def test_a_deformable_of_todays_mujoco_is_reported():
    m = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body><joint type="hinge"/><geom size="0.1"/></body>
        <flexcomp name="cloth" type="grid" count="3 3 1" spacing="0.1 0.1 0.1" dim="2"/></worldbody></mujoco>"""
    )
    assert m.nflex == 1
    with pytest.warns(UserWarning, match="1 flex object"):
        novaphy.ModelBuilder().add_mujoco_model(m)


def test_a_joint_force_range_over_several_actuators_is_named():
    m = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body><joint name="elbow" type="hinge" actuatorfrcrange="-1 1"/><geom size="0.1"/>
        </body></worldbody><actuator><motor joint="elbow"/><motor joint="elbow"/></actuator></mujoco>"""
    )
    with pytest.raises(ValueError, match="joint 'elbow' limits the force of its several actuators together"):
        novaphy.ModelBuilder().add_mujoco_model(m)


def test_a_joint_force_range_narrows_its_actuators_force_as_add_mjcf_does(tmp_path):
    xml = """<mujoco><worldbody><body><joint name="elbow" type="hinge" actuatorfrcrange="-3 2"/><geom size="0.1"/>
        </body></worldbody><actuator><motor joint="elbow" gear="2" forcerange="-1 5"/></actuator></mujoco>"""
    imported, read = novaphy.ModelBuilder(), novaphy.ModelBuilder()
    imported.add_mujoco_model(mujoco.MjModel.from_xml_string(xml))
    (tmp_path / "elbow.xml").write_text(xml)
    read.add_mjcf(str(tmp_path / "elbow.xml"))
    for model in (imported.finalize(), read.finalize()):
        # [-3, 2] over gear 2 within the actuator's own [-1, 5]
        assert (model.actuator_force_lower[0], model.actuator_force_upper[0]) == (-1.0, 1.0)


def test_an_exclusion_keeps_the_same_bodies_apart_on_both_routes(tmp_path):
    # today's MuJoCo writes an exclusion's body ids into exclude_signature as they are, 2.2.2 one higher: both
    # routes exclude the shapes of the second and third bodies (not the first's), and those two never touch
    xml = """<mujoco><worldbody>
        <body name="first" pos="3 0 0"><freejoint/><geom size="0.1"/></body>
        <body name="second"><freejoint/><geom size="0.1"/></body>
        <body name="third" pos="0.15 0 0"><freejoint/><geom size="0.1"/></body>
        </worldbody><contact><exclude body1="second" body2="third"/></contact></mujoco>"""
    (tmp_path / "excluded.xml").write_text(xml)
    imported, read = novaphy.ModelBuilder(), novaphy.ModelBuilder()
    imported.add_mujoco_model(mujoco.MjModel.from_xml_string(xml))
    read.add_mjcf(str(tmp_path / "excluded.xml"))
    for model in (imported.finalize(), read.finalize()):
        assert [list(pair) for pair in model.exclude_shape] == [[1, 2]]
        pipeline = novaphy.CollisionPipeline(model)
        contacts = pipeline.contacts()
        pipeline.collide(model.state(), contacts)
        assert contacts.contact_count == 0


def test_a_mujoco_that_writes_exclusions_another_way_is_named(monkeypatch):
    m = mujoco.MjModel.from_xml_string(
        """<mujoco><worldbody><body name="a"><freejoint/><geom size="0.1"/></body>
        <body name="b" pos="1 0 0"><freejoint/><geom size="0.1"/></body></worldbody>
        <contact><exclude body1="a" body2="b"/></contact></mujoco>"""
    )

    class Probe:  # what the binding's probe model reads as exclude_signature
        exclude_signature = np.array([7], dtype=np.int32)

        @staticmethod
        def from_xml_string(xml):
            return Probe

    monkeypatch.setattr(mujoco, "MjModel", Probe)
    with pytest.raises(ValueError, match="writes the exclusion of bodies 1 and 2 as exclude_signature 7"):
        novaphy.ModelBuilder().add_mujoco_model(m)


@pytest.mark.parametrize(
    "attribute, by_file, by_model",
    [
        (
            'pos="nan 0 1"',
            "<body name=\"b\"> pos=\"nan 0 1\": 'nan' is not a number (NaN)",
            "body_pos[1][0] (body 'b') is not finite: nan",
        ),
        (
            'pos="inf 0 1"',
            "<body name=\"b\"> pos=\"inf 0 1\": 'inf' is infinite (only a range's bounds may be)",
            "body_pos[1][0] (body 'b') is not finite: inf",
        ),
    ],
)
def test_a_value_not_finite_is_named_as_the_file_wrote_it_on_both_routes(tmp_path, attribute, by_file, by_model):
    path = tmp_path / "bad.xml"
    body = f'<body name="b" {attribute}><joint/><geom size="0.1"/></body>'
    path.write_text(f"<mujoco><worldbody>{body}</worldbody></mujoco>")
    with pytest.raises(ValueError) as raised:
        novaphy.ModelBuilder().add_mjcf(str(path))
    assert f"bad.xml line 1: {by_file}" in str(raised.value)
    with pytest.raises(ValueError) as raised:
        quiet(novaphy.from_mujoco, mujoco.MjModel.from_xml_path(str(path)))
    assert f"MjModel {by_model}" in str(raised.value)


def test_a_nan_keyframe_is_named_with_its_name_and_index(tmp_path):
    path = tmp_path / "key.xml"
    path.write_text(
        '<mujoco><worldbody><body><joint name="j"/><geom size="0.1"/></body></worldbody>'
        '<keyframe><key name="rest"/><key name="home" qpos="nan"/></keyframe></mujoco>'
    )
    with pytest.raises(ValueError, match=r"<key name=\"home\"> \(key 1 of the file\) qpos=\"nan\": 'nan' is not a"):
        novaphy.ModelBuilder().add_mjcf(str(path))
    with pytest.raises(ValueError, match=r"MjModel key_qpos\[1\]\[0\] \(keyframe 'home'\) is not finite: nan"):
        quiet(novaphy.from_mujoco, mujoco.MjModel.from_xml_path(str(path)))
