"""The studies behind the results pages of docs/results: measurements of the library, its
Python package and the path tracer, against the paper, Mitsuba 3 and other optimisers.

They are not examples of the library (those are in python/examples) and not part of the
package: each is run from the repository's root through one entry point,

    python -m studies            # the list of studies
    python -m studies NAME ARGS  # one study; NAME --help for its options

and each page it writes names the command that wrote it. Modules whose names start with ``_``
are helpers of the studies beside them; ``_page`` writes every page.
"""
