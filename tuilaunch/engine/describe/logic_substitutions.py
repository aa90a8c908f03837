"""launch's boolean and comparison substitutions: not, and, or, all, any, equals,
not-equals, if-else (`$(not ...)`, `AndSubstitution`, ...)."""

from __future__ import annotations

import math

from ..errors import LaunchError, caller_origin
from .substitutions import PerformContext, Substitution, SubValue, describe, perform, text_to_bool


class _BoolSubstitution(Substitution):
    def __init__(self, *operands: SubValue) -> None:
        self.operands = operands
        self.origin = caller_origin()

    def _bool(self, value: SubValue, context: PerformContext) -> bool:
        text = perform(value, context)
        result = text_to_bool(text)
        if result is None:
            raise LaunchError(
                f"{describe(value)} = {text!r} is not a boolean", self.origin,
                hint="use true or false",
            )
        return result


class NotSubstitution(_BoolSubstitution):
    def perform(self, context: PerformContext) -> str:
        return str(not self._bool(self.operands[0], context)).lower()


class AndSubstitution(_BoolSubstitution):
    def perform(self, context: PerformContext) -> str:
        return str(all(self._bool(v, context) for v in self.operands)).lower()


class OrSubstitution(_BoolSubstitution):
    def perform(self, context: PerformContext) -> str:
        return str(any(self._bool(v, context) for v in self.operands)).lower()


class EqualsSubstitution(Substitution):
    def __init__(self, left: SubValue, right: SubValue) -> None:
        self.left, self.right = left, right

    negate = False

    def perform(self, context: PerformContext) -> str:
        equal = _texts_equal(perform(self.left, context), perform(self.right, context))
        return str(equal != self.negate).lower()


class NotEqualsSubstitution(EqualsSubstitution):
    negate = True


def _texts_equal(left: str, right: str) -> bool:
    """launch's equality: booleans by value (True = true = 1), numbers within rounding."""
    left_bool, right_bool = text_to_bool(left), text_to_bool(right)
    if left_bool is not None and right_bool is not None:
        return left_bool == right_bool
    try:
        return math.isclose(float(left), float(right))
    except ValueError:
        return left == right


class IfElseSubstitution(Substitution):
    def __init__(self, condition: SubValue, if_value: SubValue = "", else_value: SubValue = "")\
            -> None:
        self.condition, self.if_value, self.else_value = condition, if_value, else_value
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        text = perform(self.condition, context)
        value = text_to_bool(text)
        if value is None:
            raise LaunchError(f"IfElseSubstitution condition {text!r} is not a boolean",
                              self.origin)
        return perform(self.if_value if value else self.else_value, context)


class AllSubstitution(AndSubstitution):
    """launch's AllSubstitution: true when every operand is."""


class AnySubstitution(OrSubstitution):
    """launch's AnySubstitution: true when one operand is."""
