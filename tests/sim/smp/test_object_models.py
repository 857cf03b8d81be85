"""A scenario's own object models (``models:``): a new SDF and its numbers, declared in the
file, used by its objects like a packaged model; bad declarations name file and field."""

from __future__ import annotations

import dataclasses
import math

import pytest

from tamp.errors import InputError
from tamp.sim.smp.object_models import MAX_HALF_WIDTH, PAD_REACH, object_sdf
from tamp.sim.smp.robot import OBJECT_KINDS
from tamp.sim.smp.scenario import load_scenario

from .helpers import write_one_bottle

# A crate the project does not ship: a 0.06 x 0.06 x 0.12 m box, 0.25 kg, origin at its
# centre, four small feet (1.5 mm proud) so that it stands still under point contact.
CRATE_SDF = """\
<?xml version="1.0"?>
<sdf version="1.9">
  <model name="my_crate">
    <link name="crate_body">
      <inertial>
        <mass>0.25</mass>
        <inertia>
          <ixx>0.000375</ixx><iyy>0.000375</iyy><izz>0.00015</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz>
        </inertia>
      </inertial>
      <visual name="visual">
        <geometry><box><size>0.06 0.06 0.12</size></box></geometry>
        <material><diffuse>0.5 0.5 0.5 1.0</diffuse></material>
      </visual>
      <collision name="collision">
        <geometry><box><size>0.06 0.06 0.12</size></box></geometry>
        <drake:proximity_properties>
          <drake:mu_dynamic>0.6</drake:mu_dynamic>
          <drake:mu_static>0.7</drake:mu_static>
        </drake:proximity_properties>
      </collision>
{feet}
    </link>
  </model>
</sdf>
"""
FOOT = """\
      <collision name="foot_{i}">
        <pose>{x:.4f} {y:.4f} -0.0565 0 0 0</pose>
        <geometry><sphere><radius>0.005</radius></sphere></geometry>
        <drake:proximity_properties>
          <drake:mu_dynamic>0.6</drake:mu_dynamic>
          <drake:mu_static>0.7</drake:mu_static>
        </drake:proximity_properties>
      </collision>"""
CRATE_MODEL = (
    "models:\n"
    "  crate:\n"
    "    sdf: parts/crate.sdf\n"
    "    height: 0.12\n"
    "    radius: 0.0425\n"
    "    half_width: 0.03\n"
    "    colour: [0.9, 0.8, 0.1]\n"
)
CRATE_O0 = CRATE_MODEL + "objects:\n  - {id: O0, model: crate}\n"


def write_crate(tmp_path, extra: str = CRATE_O0):
    """The crate's SDF under ``parts/`` and a one-object scenario using it."""
    (tmp_path / "parts").mkdir(exist_ok=True)
    feet = "\n".join(
        FOOT.format(i=i, x=0.02 * math.cos(a), y=0.02 * math.sin(a))
        for i, a in enumerate((0.0, math.pi / 2, math.pi, 3 * math.pi / 2))
    )
    (tmp_path / "parts" / "crate.sdf").write_text(CRATE_SDF.format(feet=feet))
    return write_one_bottle(tmp_path, extra)


def test_a_declared_model_is_used_like_a_packaged_one(tmp_path):
    s = load_scenario(write_crate(tmp_path))
    kind = s.object("O0").kind
    assert kind.name == "crate" and kind.body == "crate_body"  # its only link
    assert kind.path == (tmp_path / "parts" / "crate.sdf").resolve()
    assert (kind.half_height, kind.radius, kind.half_width) == (0.06, 0.0425, 0.03)
    assert kind.grasp_height == pytest.approx(0.06 - PAD_REACH)  # the default
    assert kind.mass == 0.25 and kind.colour == (0.9, 0.8, 0.1, 1.0)
    assert OBJECT_KINDS["bottle"].path is None  # packaged kinds are unchanged


def test_a_new_object_of_a_declared_model_takes_a_pose(tmp_path):
    extra = CRATE_MODEL + "objects:\n  - {id: C1, model: crate, pose: [1.5, -0.8, 0.3]}\n"
    s = load_scenario(write_crate(tmp_path, extra))
    c1 = s.object("C1")
    assert c1.kind.name == "crate" and c1.xy == (1.5, -0.8) and c1.yaw == 0.3
    assert s.object("O0").kind is OBJECT_KINDS["bottle"]


def test_the_model_text_is_renamed_recoloured_and_its_uris_absolute(tmp_path):
    s = load_scenario(write_crate(tmp_path))
    kind = s.object("O0").kind
    text = object_sdf(kind, "O0", friction=0.4)
    assert '<model name="O0">' in text and "my_crate" not in text
    assert "<diffuse>0.9000 0.8000 0.1000 1.0000</diffuse>" in text
    assert "<drake:mu_static>0.400000</drake:mu_static>" in text
    mesh = kind.path.parent / "crate_mesh.sdf"
    mesh.write_text(
        kind.path.read_text().replace(
            "<box><size>0.06 0.06 0.12</size></box>", "<mesh><uri>meshes/crate.obj</uri></mesh>", 1
        )
    )
    meshed = object_sdf(dataclasses.replace(kind, path=mesh), "O0")
    assert f"<uri>{(mesh.parent / 'meshes' / 'crate.obj').as_uri()}</uri>" in meshed
    # a packaged model's text is its file's, renamed
    bottle = object_sdf(OBJECT_KINDS["bottle"], "B")
    assert bottle == OBJECT_KINDS["bottle"].sdf.read_text().replace(
        '<model name="bottle">', '<model name="B">'
    )


def _bad(tmp_path, extra: str) -> InputError:
    path = write_crate(tmp_path, extra)
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.file == str(path)
    return info.value


@pytest.mark.parametrize(
    ("replace", "field", "words"),
    [
        (("parts/crate.sdf", "parts/nope.sdf"), "models.crate.sdf", "no model file"),
        (
            ("parts/crate.sdf", "package://elsewhere/crate.sdf"),
            "models.crate.sdf",
            "unknown package",
        ),
        (("parts/crate.sdf", "http://x/crate.sdf"), "models.crate.sdf", "package:// URL"),
        (
            ("    height: 0.12\n", "    height: 0.12\n    wobble: 1\n"),
            "models.crate.wobble",
            "unknown key",
        ),
        (("height: 0.12", "height: 0.05"), "models.crate.height", ">="),
        (("    radius", "    body: lid\n    radius"), "models.crate.body", "no link 'lid'"),
        (("[0.9, 0.8, 0.1]", "[1.5, 0.8, 0.1]"), "models.crate.colour[0]", "<= 1.0"),
        (("[0.9, 0.8, 0.1]", "red"), "models.crate.colour", "expected a list"),
        (("[0.9, 0.8, 0.1]", "[0.9, 0.8]"), "models.crate.colour", "at least 3"),
        (("[0.9, 0.8, 0.1]", "[0.9, 0.8, 0.1, 1, 1]"), "models.crate.colour", "[r, g, b]"),
        (("half_width: 0.03", "half_width: 0.045"), "models.crate.half_width", "radius"),
        (
            ("half_width: 0.03", "half_width: 0.05"),
            "models.crate.half_width",
            f"<= {MAX_HALF_WIDTH}",
        ),
        (
            ("    half_width: 0.03\n", "    grasp_height: 0.03\n"),
            "models.crate.grasp_height",
            "pads",
        ),
        (("  crate:\n", "  bottle:\n"), "models.bottle", "packaged model"),
        (("model: crate}", "model: crates}"), "objects[0].model", "unknown model 'crates'"),
    ],
)
def test_bad_declarations_name_the_field(tmp_path, replace, field, words):
    err = _bad(tmp_path, CRATE_O0.replace(*replace))
    assert err.field == field and words in err.reason, err


def test_a_model_file_that_is_not_sdformat_is_refused(tmp_path):
    path = write_crate(tmp_path)
    (tmp_path / "parts" / "crate.sdf").write_text("<robot name='x'><link name='a'/></robot>")
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.field == "models.crate.sdf" and "one <model>" in info.value.reason
    (tmp_path / "parts" / "crate.sdf").write_text("not xml <")
    with pytest.raises(InputError) as info:
        load_scenario(path)
    assert info.value.field == "models.crate.sdf" and "not an SDFormat file" in info.value.reason


@pytest.mark.slow
def test_an_object_of_a_declared_model_is_picked_and_placed_in_drake(tmp_path):
    """The crate is in the plant (its own body, the declared colour) and the robot carries
    it to its goal: the whole one-object task succeeds."""
    from pydrake.geometry import Role

    from tamp.sim.smp.runner import SimRunner
    from tamp.sim.smp.simulate import prepare
    from tamp.sim.smp.station import build_station

    scenario = load_scenario(write_crate(tmp_path))
    system = build_station(scenario, prepare(scenario).policy)
    plant = system.plant
    body = system.bodies["O0"]
    assert body.name() == "crate_body" and plant.GetModelInstanceName(body.model_instance()) == "O0"
    assert body.default_mass() == pytest.approx(0.25)
    inspector = system.diagram.GetSubsystemByName("scene_graph").model_inspector()
    (visual,) = inspector.GetGeometries(
        plant.GetBodyFrameIdOrThrow(body.index()), Role.kIllustration
    )
    rgba = inspector.GetIllustrationProperties(visual).GetProperty("phong", "diffuse")
    assert (rgba.r(), rgba.g(), rgba.b()) == pytest.approx((0.9, 0.8, 0.1))
    result = SimRunner(system).run()
    assert result.status == "SUCCESS", result.reason
    pose = result.final_poses["O0"]
    assert math.hypot(pose.x - 1.0, pose.y - 0.7) < 0.15  # on its goal area L0
    assert abs(pose.z - 0.06) < 0.01  # standing upright on the floor
