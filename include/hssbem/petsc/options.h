/* hssbem's options (core/option_table.hpp) in PETSc's options database: each read by its row of
   the table, with the row's default and range, so that no reader keeps a default or a bound of
   its own. The driver reads its rows silently (PetscOptionsGet*: it prints -help from the table
   itself); PETSc objects (PC h2, PC hss) read theirs in their SetFromOptions with the *Item
   functions, which PETSc's -help lists as it does any object's. */
#pragma once

#include "hssbem/petsc/compat.h"

#include "hssbem/core/option_table.hpp"

#include <petscsys.h>

/* The row of option `name` (without the dash); PETSC_ERR_PLIB when the table has none. */
PetscErrorCode HssbemOptionRow(const char *name, const hssbem::OptionRow **row);

/* The value of `row` (with `prefix`, may be NULL) when the database holds it (*set), parsed as
   the row's kind and checked against its range (PETSC_ERR_ARG_OUTOFRANGE naming the option);
   marks it used. *value is left alone when it is not given. */
PetscErrorCode HssbemOptionsGetValue(MPI_Comm comm, const char *prefix, const hssbem::OptionRow &row, hssbem::OptionValue *value, PetscBool *set);

/* Every row that `reader` reads and that applies to one of `jobs`, given in the database, into
   values (those not given are left out: their defaults are the table's). */
PetscErrorCode HssbemOptionsGetValues(MPI_Comm comm, const char *prefix, hssbem::OptionReader reader, unsigned jobs, hssbem::OptionValues *values);

/* Inside an object's PetscOptionsBegin/End (its SetFromOptions): the option `name` with the
   row's help line, `*value` holding the current value on entry (the table's default until set),
   checked against the row's range. `manual` names the setter (PETSc's -help shows it). */
PetscErrorCode HssbemOptionsRealItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscReal *value);
PetscErrorCode HssbemOptionsIntItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscInt *value);
PetscErrorCode HssbemOptionsBoolItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscBool *value);

/* values[name] = value, of the kind of option `name`'s row (for the values an object reports). */
PetscErrorCode HssbemOptionValuePut(hssbem::OptionValues *values, const char *name, double value);

/* PETSC_ERR_ARG_OUTOFRANGE on comm with the table's message when `value` is no value of
   option `name` (a setter's check: PCH2SetRelTol(pc, 2) fails as -pc_h2_rel_tol 2 does). */
PetscErrorCode HssbemOptionCheck(MPI_Comm comm, const char *name, double value);
