"""The kept list of synced models (app.message_tuning) gives the messages Bokeh's own code gives,
as models are added, sent, changed and removed."""
from __future__ import annotations

import json

from bokeh.core.serialization import Serializer
from bokeh.document import Document
from bokeh.models import ColumnDataSource, Column, Div
from bokeh.protocol import Protocol

from app import message_tuning


def _bokeh_synced(doc) -> set:
    """Bokeh's own definition of the models the page already has."""
    return {m for m in doc.models._models.values() if m not in doc.models._new_models}


def _message_and_expected(doc, events):
    """The PATCH-DOC content as sent (patched), and as Bokeh's own serializer makes it."""
    expected = Serializer(references=_bokeh_synced(doc)).encode(events)  # a plain set: Bokeh's path
    msg = Protocol().create("PATCH-DOC", events)
    return json.loads(msg.content_json)["events"], json.loads(json.dumps(expected, default=dict))


def _recorded(doc):
    events = []
    doc.on_change(events.append)
    return events


def test_install_is_idempotent_and_in_place():
    assert message_tuning.install() and message_tuning.install()
    assert getattr(Serializer, "_amra_kept_refs", False)


def test_the_kept_list_follows_the_document_and_messages_match_bokehs():
    assert message_tuning.install()
    doc = Document()
    source = ColumnDataSource({"x": [1.0, 2.0]})
    col = Column(children=[Div(text="a")])
    doc.add_root(col)
    doc.add_root(source)
    events = _recorded(doc)
    assert doc.models.synced_references == _bokeh_synced(doc) == set()  # nothing sent yet

    doc.models.flush_synced()  # the page has everything (as after its first pull)
    first = doc.models.synced_references
    assert first == _bokeh_synced(doc) and len(first) == len(doc.models) > 0
    assert doc.models.synced_references is first  # kept, not rebuilt
    assert first.refs == {id(m): m.ref for m in first}

    col.children[0].text = "b"  # a change: same models, a reference in the message
    sent, expected = _message_and_expected(doc, events[-1:])
    assert sent == expected and doc.models.synced_references is first

    new_div = Div(text="new")
    col.children = [*col.children, new_div]  # a new model: sent whole, then known
    assert new_div not in doc.models.synced_references
    assert doc.models.synced_references == _bokeh_synced(doc)
    sent, expected = _message_and_expected(doc, events[-1:])
    assert sent == expected and any(e.get("kind") == "ModelChanged" for e in sent)
    assert '"type":"object"' in json.dumps(sent, separators=(",", ":"))  # the whole new Div
    assert new_div in doc.models.synced_references == _bokeh_synced(doc)  # flushed by the message

    source.stream({"x": [3.0]})
    sent, expected = _message_and_expected(doc, events[-1:])
    assert sent == expected and sent[0]["kind"] == "ColumnsStreamed"

    col.children = col.children[:1]  # a model removed
    assert new_div not in doc.models.synced_references
    assert doc.models.synced_references == _bokeh_synced(doc)
    sent, expected = _message_and_expected(doc, events[-1:])
    assert sent == expected


def test_a_plain_reference_set_still_takes_bokehs_path():
    assert message_tuning.install()
    div = Div(text="x")
    assert Serializer(references={div}).get_ref(div) == div.ref
    assert Serializer().get_ref(div) is None
