"""AMRA's Panel dashboard (served with ``panel serve app/main.py``)."""
