"""Server-side tuning of Bokeh's document messages: the list of models a page already has is kept,
not rebuilt for every message.

Each change Bokeh sends a session's page (a PATCH-DOC message: every streamed batch, every status
text) starts by listing every model the page already knows (``DocumentModelManager.synced_references``,
a new set of all ~350 models of the session) and making a reference for each
(``Serializer.__init__``: ``{id(model): model.ref}``), however small the change. With eight
sessions streaming, that was 17 % of the event loop's time, which all sessions and their users'
input share (py-spy of the server, 2026-12-02: 100 of 590 main-thread samples). The list changes
only when the document's model table is replaced or resized (``recompute`` after models are added
or removed) or its set of not-yet-sent models changes; it is now kept per document and rebuilt then,
and each message copies the references (a dict copy) instead of making them anew.

:func:`install` patches Bokeh once per process, and only a Bokeh whose internals look as expected
(else it leaves Bokeh as it is); ``tests/app/test_message_tuning.py`` checks that messages are the
same as Bokeh's own, models added and removed included.
"""
from __future__ import annotations

from bokeh.core.serialization import Serializer
from bokeh.document.models import DocumentModelManager


class SyncedModels(frozenset):
    """The models a page already has, with their references made once (``refs``: id -> Ref)."""

    refs: dict


def synced_models(manager: DocumentModelManager) -> SyncedModels:
    """``manager.synced_references``, kept until the model table or the set of new models changes."""
    table, new = manager._models, frozenset(manager._new_models)
    kept = manager.__dict__.get("_amra_synced")
    if kept is None or kept[0] is not table or kept[1] != len(table) or kept[2] != new:
        models = SyncedModels(m for m in table.values() if m not in new)
        models.refs = {id(m): m.ref for m in models}
        kept = (table, len(table), new, models)  # holds the table: its id cannot be reused meanwhile
        manager._amra_synced = kept
    return kept[3]


def _looks_as_expected() -> bool:
    manager_ok = isinstance(getattr(DocumentModelManager, "synced_references", None), property)
    probe = Serializer(references=set())
    return manager_ok and isinstance(getattr(probe, "_references", None), dict)


def install() -> bool:
    """Patch Bokeh (once per process); returns whether the patch is in place."""
    if getattr(Serializer, "_amra_kept_refs", False):
        return True
    if not _looks_as_expected():
        return False
    make_refs = Serializer.__init__

    def __init__(self, *, references=frozenset(), **kwargs):
        if isinstance(references, SyncedModels):
            make_refs(self, references=(), **kwargs)
            self._references = dict(references.refs)
        else:
            make_refs(self, references=references, **kwargs)

    Serializer.__init__ = __init__
    DocumentModelManager.synced_references = property(synced_models)
    Serializer._amra_kept_refs = True
    return True
