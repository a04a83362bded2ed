"""Helpers of scripts/peers: scene conversion (convert.py, standard library only), the peer
render worker (worker.py, run by the Python that has mitsuba/pyluxcore), the conversion check
(check.py) and the report (report.py)."""
