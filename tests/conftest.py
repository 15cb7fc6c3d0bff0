"""pytest configuration shared by every test: the hypothesis profile.

Property tests are derandomized (the same examples on every run, so CI is reproducible) and have no
per-example deadline (the machines are shared; speed lives in benchmarks, not in tests).
"""

from hypothesis import settings

settings.register_profile("vqtex", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("vqtex")
