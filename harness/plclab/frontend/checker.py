"""Semantic checks of an ST compilation unit, as strict as OpenPLC's matiec.

The checker resolves every name, types every expression (annotating the AST in place, see
plclab.frontend.ast), evaluates constant expressions (array bounds, CASE labels, initial
values, task intervals) and collects every error it can find in one pass, each with its
source position. Types follow matiec: no implicit conversion between differently typed
variables; an untyped literal takes the type its context needs if its value fits.

The checker is assembled from one part per concern: check_types (declarations and types),
check_statements (bodies and FB calls), check_expressions (expressions, calls, overloads) and
check_config (the CONFIGURATION) and check_limits (declared memory, nesting, POUs that refer
to themselves), over check_base (shared state and rules).
"""
from __future__ import annotations

from plclab.frontend import ast as A
from plclab.frontend.check_config import ConfigurationChecks
from plclab.frontend.check_expressions import ExpressionChecks
from plclab.frontend.check_limits import LimitChecks
from plclab.frontend.check_statements import StatementChecks
from plclab.frontend.check_types import DeclarationChecks
from plclab.frontend.checked import CheckedUnit
from plclab.iec import types as T


class Checker(DeclarationChecks, StatementChecks, ExpressionChecks, ConfigurationChecks, LimitChecks):
    """Checks one compilation unit: every part's checks, driven in matiec's order."""

    # ------------------------------------------------------------------ driver
    def check(self) -> CheckedUnit:
        u = self.unit
        for td in u.types:
            if self._declare_name(td, td.name, "type"):
                self.type_decls[td.key] = td
        for pou in u.pous:
            if self._declare_name(pou, pou.name, pou.kind.lower().replace("_", " ")):
                self.pous[pou.key] = pou
                if pou.kind == "FUNCTION_BLOCK":
                    self.fb_types[pou.key] = T.FBType(pou.name, pou)
        for td in u.types:
            self._resolve_type_decl(td)
        # configuration-level globals (GVL files count as the configuration's own)
        config = u.configs[0] if u.configs else None
        if len(u.configs) > 1:
            for c in u.configs[1:]:
                self.error(c, "only one CONFIGURATION is allowed in a program")
        # Global scopes. Inside a CONFIGURATION there is one. Without one, each GVL file is a
        # scope of its own: the files of several stands can be checked together (`plclab
        # check plc/GVL/*.st ...`), each POU against the GVL that declares its
        # VAR_EXTERNALs, although two stands' consoles both have an SB1.
        config_blocks = []
        if config:
            config_blocks += config.globals
            for res in config.resources:
                config_blocks += res.globals
        scopes: dict[str, list[A.VarBlock]] = {}
        for block in u.gvls:
            scopes.setdefault("" if config else block.file, []).append(block)
        if config or not scopes:
            scopes = {"": list(u.gvls) + config_blocks}
        self.global_scopes: list[dict[str, A.VarDecl]] = []
        for blocks in scopes.values():
            self.globals = {}
            for block in blocks:
                self._check_block_rules(block, None)
                for d in block.decls:
                    self._declare_var(d, self.globals, None)
            self.global_scopes.append(self.globals)
        for pou in u.pous:
            if pou.key in self.pous and self.pous[pou.key] is pou:
                self.globals = self._scope_for(pou)
                self._check_pou_decls(pou)
        self.globals = self.global_scopes[0]
        for pou in u.pous:
            if pou.key in self.pous and self.pous[pou.key] is pou:
                self._check_pou_body(pou)
        if config:
            self._check_config(config)
        self._check_limits(config)
        return CheckedUnit(u, self.types, self.pous, self.globals, config, sorted(set(self.diags)),
                           len(self.global_scopes))


def check_unit(unit: A.Unit) -> CheckedUnit:
    return Checker(unit).check()
