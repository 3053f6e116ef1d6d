import os

import pytest

SCENES = os.path.join(os.path.dirname(__file__), "..", "..", "bench", "scenes")
HUMANOID = "/usr/share/mujoco/model/humanoid/humanoid.xml"


@pytest.fixture
def scene():
    return lambda name: os.path.join(SCENES, name)
