"""Specs of a YAML document a person edits (:class:`Obj`, :class:`Num`, :class:`Str`, ...): each
checks a node, collects every problem with its position, and generates its JSON Schema.

The base spec and the scalars are in :mod:`.scalars`; lists, mappings with known keys and
a whole document checked at once in :mod:`.compound`.
"""

from rodcad.yamlspec.compound import CrossCheck, Checked, Field, ListOf, Obj, OneOrList, check_document
from rodcad.yamlspec.scalars import MAX_MAGNITUDE, Any_, Bool, Nullable, Num, Spec, Str

__all__ = ['MAX_MAGNITUDE', 'Spec', 'Any_', 'Str', 'Bool', 'Num', 'Nullable', 'ListOf', 'OneOrList', 'Field',
           'CrossCheck', 'Obj', 'Checked', 'check_document']
