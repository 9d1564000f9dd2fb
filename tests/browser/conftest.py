def pytest_configure(config):
    config.addinivalue_line("markers", "smoke: the short browser check CI runs (.ci/run)")
