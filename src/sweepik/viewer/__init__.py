"""The browser viewer (``sweepik view``, :func:`sweepik.view`): every solution of a target drawn at once, on viser.

``scene`` computes what is drawn (plain arrays); ``app`` serves it (viser, the ``view`` extra).
"""
