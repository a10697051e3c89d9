"""Drawing in the one look: colours and legends (``style``), the static figures of a run
(``plots``), obstacles as boxes (``boxes``). Strategies and the core draw with it; the
commands that read run folders back live in :mod:`tether.viewing`."""
