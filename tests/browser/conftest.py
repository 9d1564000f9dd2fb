import pytest

from ikteach.course import book
from labdriver import chromium


def pytest_configure(config):
    config.addinivalue_line("markers", "smoke: the short browser check CI runs (.ci/run)")


@pytest.fixture(scope="session")
def site():
    """The book with its decks (slides/), in build/test-site: the one `make test` built
    (tests/test_site.py) when it was built from the same files, else built now."""
    return book.build(book.TESTED, reuse=True)


@pytest.fixture(scope="session")
def book_browser():
    """One headless Chromium for the book's pages and the decks (site_book, site_slides): each
    test sets the window it needs."""
    with chromium() as driver:
        yield driver
