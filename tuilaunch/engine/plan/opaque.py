"""OpaqueFunctions, SimpleLauncher's opaque mode and third-party actions' execute(): user
code run while the plan is made, whose errors name the user's file and line."""

from __future__ import annotations

import sys
from typing import Any

from ..describe.entities import DslOpaque, Entity, OpaqueFunction, entity_list
from ..describe.environ import Overlay, captured_environ
from ..describe.python.loader import compat_modules, known_launch_files, unsupported_import
from ..describe.substitutions import PerformContext
from ..errors import LaunchError, origin_from_traceback, origin_outside_tuilaunch


def is_custom_action(entity: Any) -> bool:
    """A launch.Action subclass written outside tuilaunch: it runs through execute()."""
    return isinstance(entity, Entity) and callable(getattr(entity, "execute", None))


def perform_opaque(entity: Any, context: PerformContext) -> tuple[list[Any], Overlay]:
    """The entities an opaque entity produces in this context, and what it wrote into
    os.environ (launch keeps that for what follows)."""
    try:
        with compat_modules(), captured_environ() as environ:
            if isinstance(entity, DslOpaque):
                with entity.launcher.opaque_scope(context) as root:
                    result = entity.function()
                produced = entity_list(result) if result is not None else [root]
            elif not isinstance(entity, OpaqueFunction):
                produced = entity_list(entity.execute(context))
            else:
                produced = entity_list(entity.function(context, *entity.args,
                                                       **entity.kwargs))
    except (LaunchError, BrokenPipeError):  # a closed stdout is the reader's choice
        raise
    except Exception as exc:  # user code: report its own file and line
        tb = sys.exc_info()[2]
        origin = origin_outside_tuilaunch(tb) or origin_from_traceback(
            tb, known_launch_files())
        missing = unsupported_import(exc) if isinstance(exc, ImportError | AttributeError) \
            else None
        what = "the opaque function" if isinstance(entity, OpaqueFunction | DslOpaque) \
            else f"{type(entity).__name__}.execute()"
        raise LaunchError(missing or f"{what} raised {type(exc).__name__}: {exc}",
                          origin or entity.origin) from None
    return produced, environ
