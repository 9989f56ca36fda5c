import pytest

from phantom_cad import load_hand


@pytest.fixture(scope="session")
def hand():
    return load_hand()
