"""What a user edits, shared by the studio's :class:`~engine.studio.session.Session` and the
pose window's :class:`~engine.authoring.session.AuthoringSession`; Qt-free.

* :mod:`engine.editing.constraint_list`: the constraint list, a sub-model whose edits
  replace objects and fire one :class:`~engine.editing.events.ConstraintsChanged` each.
* :mod:`engine.editing.catalog`: the constraint kinds users may add, with their fields.
* :mod:`engine.editing.events`: the list's event payload (no heavy imports).

Both session packages build on this one, so neither imports the other for it.
"""
