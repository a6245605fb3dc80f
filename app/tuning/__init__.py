"""Work-arounds for framework bugs, each applied only on the exact versions it was checked on, each
with an upstream-ready reproducer in docs/upstream/. Nothing else in app/ touches framework internals."""
