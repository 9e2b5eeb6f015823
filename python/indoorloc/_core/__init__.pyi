# Type stubs of the compiled module indoorloc._core (kept in sync by tests/python/test_stubs.py).
from . import analog as analog
from . import core as core
from . import fusion as fusion
from . import mapmatch as mapmatch
from . import network as network
from . import pdr as pdr
from . import wifi as wifi

__version__: str
