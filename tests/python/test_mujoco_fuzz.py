"""A compiled mujoco.MjModel with corrupted index, address, count, type and value fields through
novaphy.from_mujoco: every conversion either succeeds or raises ValueError, never crashes. Each seeded batch runs
in a subprocess, so a segfault fails its test instead of ending pytest; the targeted tests check one message per
class of field. Skipped where PyPI's mujoco is not installed (tools/setup.sh installs it into build/venv)."""

import copy
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import novaphy

mujoco = pytest.importorskip(
    "mujoco", reason="PyPI's mujoco is not installed for this interpreter (tools/setup.sh puts it in build/venv)"
)

MODEL = os.path.join(os.path.dirname(__file__), "models", "fuzz.xml")
ROBOTS = os.environ.get("MENAGERIE_ROOT") or os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "robots")
# the fuzz model (every kind of element the converter reads) under four seeds, and two Menagerie robots where on disk
FUZZED = [(MODEL, seed) for seed in range(4)] + [
    (os.path.join(ROBOTS, "unitree_go1", "go1.xml"), 0),
    (os.path.join(ROBOTS, "franka_emika_panda", "panda.xml"), 0),
]

# the integer fields the converter reads as indices, addresses, counts or types, and others beside them
INDEX_FIELDS = (
    "body_parentid body_jntnum body_jntadr jnt_type jnt_qposadr jnt_dofadr geom_type geom_bodyid geom_dataid "
    "geom_contype geom_conaffinity geom_condim geom_priority mesh_vertadr mesh_vertnum exclude_signature tendon_adr "
    "tendon_num wrap_type wrap_objid actuator_trntype actuator_dyntype actuator_gaintype actuator_biastype "
    "actuator_trnid eq_type eq_obj1id eq_obj2id eq_objtype name_bodyadr name_jntadr name_geomadr name_meshadr "
    "name_tendonadr name_actuatoradr name_keyadr name_eqadr"
).split()
# the floating-point fields the converter reads
VALUE_FIELDS = (
    "body_pos body_quat body_ipos body_iquat body_mass body_inertia jnt_pos jnt_axis jnt_range qpos0 geom_pos "
    "geom_quat geom_size key_qpos key_qvel key_ctrl eq_data actuator_gear wrap_prm"
).split()
COUNTS = "nq nv nu nbody njnt ngeom ntendon nkey neq nmesh nmeshvert nwrap".split()


class Corrupted:
    """An MjModel with some attributes replaced (counts and names, which MjModel does not let one write)."""

    def __init__(self, model, **replaced):
        self._model = model
        self._replaced = replaced

    def __getattr__(self, name):
        return self._replaced[name] if name in self._replaced else getattr(self._model, name)


def corrupt(model, rng):
    """A copy of `model` with one to three fields corrupted, and what was done."""
    m = copy.copy(model)
    replaced, done = {}, []
    for _ in range(rng.integers(1, 4)):
        kind = rng.random()
        if kind < 0.6:
            name = str(rng.choice(INDEX_FIELDS))
            field = getattr(m, name)
            if field.size == 0:
                continue
            size = max(field.shape[0], 1)
            value = int(rng.choice([-1, -2, size, size + 1, 2**31 - 1, -(2**31), rng.integers(-50, 50)]))
            index = tuple(int(rng.integers(0, s)) for s in field.shape)
            field[index] = value
        elif kind < 0.85:
            name = str(rng.choice(VALUE_FIELDS))
            field = getattr(m, name)
            if field.size == 0:
                continue
            value = float(rng.choice([np.nan, np.inf, -np.inf, 0.0, 1e300, -1e300]))
            index = tuple(int(rng.integers(0, s)) for s in field.shape)
            field[index] = value
        elif kind < 0.95:
            name = str(rng.choice(COUNTS))
            value = int(rng.choice([-1, 0, getattr(m, name) + 1, 2**31 - 1, 2**40]))
            replaced[name] = value
            index = ()
        else:
            name, index = "names", ()
            value = getattr(m, "names").replace(b"\0", b"x")  # no name ends
            replaced[name] = value
        done.append(f"{name}{list(index)} = {value!r}"[:80])
    return (Corrupted(m, **replaced) if replaced else m), done


def fuzz(path, seed, trials):
    """`trials` corrupted copies of the model at `path` through from_mujoco; anything but ValueError escapes."""
    warnings.simplefilter("ignore")
    model = mujoco.MjModel.from_xml_path(path)
    rng = np.random.default_rng(seed)
    raised = 0
    for trial in range(trials):
        m, done = corrupt(model, rng)
        print(f"seed {seed} trial {trial}: {'; '.join(done)}", flush=True)
        try:
            novaphy.from_mujoco(m)
        except ValueError:
            raised += 1
    print(f"{raised} of {trials} raised ValueError", flush=True)


@pytest.mark.parametrize("path, seed", FUZZED, ids=lambda x: os.path.basename(x) if isinstance(x, str) else str(x))
def test_corrupted_fields_raise_value_error_or_convert_never_crash(path, seed):
    if not os.path.exists(path):
        pytest.skip(f"{path} is not on disk (set MENAGERIE_ROOT)")
    here = os.path.dirname(os.path.abspath(__file__))
    code = f"import sys; sys.path.insert(0, {here!r}); import test_mujoco_fuzz as f; f.fuzz({path!r}, {seed}, 100)"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    last = run.stdout.strip().splitlines()[-3:]
    assert run.returncode == 0, f"exit {run.returncode} after:\n" + "\n".join(last) + "\n" + run.stderr[-2000:]
    raised = int(last[-1].split()[0])
    assert raised > 50, last[-1]  # most corruptions are caught, not converted


def convert(m):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        novaphy.from_mujoco(m)


@pytest.fixture
def model():
    return mujoco.MjModel.from_xml_path(MODEL)


@pytest.mark.parametrize(
    "field, index, value, message",
    [
        ("jnt_qposadr", 2, 99, "MjModel jnt_qposadr[2] (joint 'elbow'): 99 out of range [0, 14)"),
        ("jnt_qposadr", 2, 12, "MjModel jnt_qposadr[2] (joint 'elbow'): 12, expected 11"),
        ("jnt_dofadr", 3, -1, "MjModel jnt_dofadr[3] (joint 'slider'): -1 out of range [0, 12)"),
        ("jnt_type", 1, 4, "MjModel jnt_type[1] (joint 'shoulder'): 4 out of range [0, 4)"),
        ("body_parentid", 3, 3, "MjModel body_parentid[3] (body 'lower'): 3 out of range [0, 3)"),
        ("body_jntadr", 2, 0, "MjModel body_jntadr[2] (body 'upper'): 0, expected 1"),
        ("geom_bodyid", 3, 6, "MjModel geom_bodyid[3] (geom 'lower'): 6 out of range [0, 6)"),
        ("geom_type", 1, 100, "MjModel geom_type[1] (geom 'torso'): 100 out of range [0, 9)"),
        ("geom_dataid", 3, 1, "MjModel geom_dataid[3] (geom 'lower'): 1 out of range [0, 1)"),
        ("mesh_vertnum", 0, 5, "MjModel mesh_vertnum[0] (mesh 'tetra'): 5 out of range [0, 5)"),
        ("actuator_trnid", (0, 0), 5, "MjModel actuator_trnid[0][0] (actuator 'elbow'): 5 out of range [0, 5)"),
        ("actuator_trnid", (1, 0), 1, "MjModel actuator_trnid[1][0] (actuator 'pull'): 1 out of range [0, 1)"),
        ("actuator_trntype", 0, -3, "MjModel actuator_trntype[0] (actuator 'elbow'): -3 out of range [0, 7)"),
        ("eq_obj2id", 0, 6, "MjModel eq_obj2id[0] (equality 'hold'): 6 out of range [-1, 6)"),
        ("eq_type", 2, 8, "MjModel eq_type[2] (equality 'pair'): 8 out of range [0, 8)"),
        ("tendon_adr", 0, 2, "MjModel tendon_adr[0] (tendon 'coupled'): 2 out of range [0, 2)"),
        ("wrap_objid", 1, -1, "MjModel wrap_objid[1] (tendon 'coupled'): -1 out of range [0, 5)"),
        ("exclude_signature", 0, 7 << 16 | 1, "MjModel exclude_signature[0] (its first body): 7 out of range [0, 6)"),
        ("name_geomadr", 2, -5, "MjModel name_geomadr[2] (geom 2): -5 out of range [0, "),
        ("key_qpos", (0, 11), np.nan, "MjModel key_qpos[0][11] (keyframe 'home') is not finite: nan"),
        ("body_pos", (2, 1), np.inf, "MjModel body_pos[2][1] (body 'upper') is not finite: inf"),
        ("geom_quat", 1, 0, "MjModel geom_quat[1] (geom 'torso') is a zero quaternion"),
        ("qpos0", 11, -np.nan, "MjModel qpos0[11] (joint 'elbow') is not finite: nan"),
    ],
)
def test_each_corrupted_field_is_named_with_its_element_and_value(model, field, index, value, message):
    getattr(model, field)[index] = value
    with pytest.raises(ValueError) as raised:
        convert(model)
    assert message in str(raised.value)


def test_corrupted_counts_and_names_are_named(model):
    with pytest.raises(ValueError, match=r"the MjModel's field 'qpos0' is not 15 x 1 values"):
        convert(Corrupted(model, nq=15))
    with pytest.raises(ValueError, match=r"the MjModel's count 'nbody' is not an int of 32 bits: 1099511627776"):
        convert(Corrupted(model, nbody=2**40))
    end = model.name_keyadr[0]  # the last name, the keyframe's
    assert model.names[end:] == b"home\0"
    with pytest.raises(ValueError, match=rf"MjModel name_keyadr\[0\] \(keyframe 0\): the name at {end} has no NUL"):
        convert(Corrupted(model, names=model.names[:-1] + b"x"))


def test_the_fuzz_model_converts_as_it_is(model):
    convert(model)
