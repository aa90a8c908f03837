"""If/unless conditions, evaluated per resolve, each reporting what it read."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import ArgumentError, LaunchError, Origin, caller_origin
from .substitutions import (
    LaunchConfiguration,
    PerformContext,
    SimpleSubstitution,
    SubValue,
    describe,
    flatten,
    perform,
    text_to_bool,
)


@dataclass(frozen=True)
class ConditionOutcome:
    """What a condition read and decided: shown for skipped branches and in the tree."""

    expression: str
    value: str
    holds: bool

    def to_json(self) -> dict[str, object]:
        return {"expression": self.expression, "value": self.value, "holds": self.holds}


def _argument_name(predicate: SubValue) -> str | None:
    parts = flatten(predicate)
    while len(parts) == 1 and isinstance(parts[0], SimpleSubstitution):
        parts = parts[0].parts
    if len(parts) == 1 and isinstance(parts[0], LaunchConfiguration):
        return parts[0].name()
    return None


class Condition:
    """launch.Condition: `evaluate(context)` is a bool, as launch's is.

    Third-party conditions pass `predicate=` (a function of the context) or override
    `evaluate`; ours override `outcome`, which also says what was read, for the tree."""

    origin: Origin | None = None

    def __init__(self, *, predicate: Any = None) -> None:
        self._predicate = predicate
        self.origin = caller_origin()

    def outcome(self, context: PerformContext) -> ConditionOutcome:
        predicate = getattr(self, "_predicate", None)
        if predicate is None:
            return ConditionOutcome(self.describe(), "", True)
        holds = _guarded(lambda: bool(predicate(context)), self, "predicate")
        return ConditionOutcome(self.describe(), str(holds).lower(), holds)

    def evaluate(self, context: PerformContext) -> bool:
        return self.outcome(context).holds

    def describe(self) -> str:
        return type(self).__name__


def condition_outcome(condition: Any, context: PerformContext) -> ConditionOutcome:
    """What a condition decided, whoever wrote it (ours, a subclass, a duck-typed one)."""
    if isinstance(condition, Condition) and type(condition).evaluate is Condition.evaluate:
        return condition.outcome(context)
    holds = _guarded(lambda: bool(condition.evaluate(context)), condition, "evaluate()")
    text = condition.describe() if hasattr(condition, "describe") else type(condition).__name__
    return ConditionOutcome(text, str(holds).lower(), holds)


def _guarded(call: Any, condition: Any, what: str) -> bool:
    import sys

    try:
        return bool(call())
    except LaunchError:
        raise
    except Exception as exc:  # a third-party condition's own error, at its own line
        from ..errors import origin_outside_tuilaunch

        where = origin_outside_tuilaunch(sys.exc_info()[2]) or getattr(condition, "origin", None)
        raise LaunchError(f"{type(condition).__name__} {what} raised "
                          f"{type(exc).__name__}: {exc}", where) from None


class InvalidConditionExpressionError(ArgumentError):
    """launch.conditions.InvalidConditionExpressionError."""

    def __init__(self, expression: str, *_: Any) -> None:
        super().__init__(f"condition {expression!r} is not a boolean", caller_origin())


def evaluate_condition_expression(context: PerformContext, expression: SubValue) -> bool:
    """launch.conditions.evaluate_condition_expression: true/false/1/0, any case."""
    text = perform(expression, context)
    value = text_to_bool(text)
    if value is None:
        raise InvalidConditionExpressionError(text)
    return value


class IfCondition(Condition):
    negate = False

    def __init__(self, predicate_expression: SubValue) -> None:
        self.predicate = predicate_expression
        self.origin = caller_origin()

    def describe(self) -> str:
        word = "unless" if self.negate else "if"
        return f"{word} {describe(self.predicate)}"

    def outcome(self, context: PerformContext) -> ConditionOutcome:
        if isinstance(self.predicate, bool):
            text = str(self.predicate).lower()
        else:
            text = perform(self.predicate, context)
        value = text_to_bool(text)
        if value is None:
            name = _argument_name(self.predicate)
            if name is not None:
                raise ArgumentError(
                    f"argument '{name}' = {text!r} is used as a condition but is not a boolean",
                    self.origin,
                    hint=f"pass {name}:=true or {name}:=false",
                )
            raise ArgumentError(
                f"condition {describe(self.predicate)} gave {text!r}, which is not a boolean",
                self.origin,
                hint="a condition must read true, false, 1 or 0",
            )
        holds = (not value) if self.negate else value
        return ConditionOutcome(self.describe(), text, holds)


class UnlessCondition(IfCondition):
    negate = True


class LaunchConfigurationEquals(Condition):
    negate = False

    def __init__(self, launch_configuration_name: str, expected_value: SubValue) -> None:
        self.name = launch_configuration_name
        self.expected = expected_value
        self.origin = caller_origin()

    def describe(self) -> str:
        op = "!=" if self.negate else "=="
        return f"$(var {self.name}) {op} {describe(self.expected)!r}"

    def outcome(self, context: PerformContext) -> ConditionOutcome:
        value = context.configurations.get(self.name, "")
        expected = "" if self.expected is None else perform(self.expected, context)
        equal = value == expected
        return ConditionOutcome(self.describe(), value, equal != self.negate)


class LaunchConfigurationNotEquals(LaunchConfigurationEquals):
    negate = True


def as_condition(value: object, negate: bool = False) -> Condition:
    """Anything a user may pass as a condition (bool, substitution, Condition)."""
    if isinstance(value, Condition):
        return value
    return UnlessCondition(value) if negate else IfCondition(value)
