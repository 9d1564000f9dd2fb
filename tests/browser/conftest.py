import pytest

from ikteach.course import book


def pytest_configure(config):
    config.addinivalue_line("markers", "smoke: the short browser check CI runs (.ci/run)")


@pytest.fixture(scope="session")
def site(tmp_path_factory):
    """The book with its decks (build/site/slides), built once for the browser tests."""
    return book.build(tmp_path_factory.mktemp("book") / "site")
