"""Submodules loaded on first use: `package.name` imports `package.name` the first time."""
import importlib


def submodules(package_name, package_globals):
    """A module __getattr__ that imports the package's submodule `name` on first use."""
    def __getattr__(name):
        if name.startswith("__"):
            raise AttributeError(name)
        try:
            module = importlib.import_module(f"{package_name}.{name}")
        except ModuleNotFoundError as err:
            if err.name != f"{package_name}.{name}":
                raise
            raise AttributeError(f"module {package_name!r} has no attribute {name!r}") from None
        package_globals[name] = module
        return module
    return __getattr__
