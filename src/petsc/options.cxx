/* hssbem's options in PETSc's options database, read by their rows of the table (see options.h). */
#include "hssbem/petsc/options.h"

#include <string>

/*@C
  HssbemOptionRow - The row of an option in hssbem's table (core/option_table.def).

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemOptionRow(const char *name, const hssbem::OptionRow **row)
{
  PetscFunctionBegin;
  *row = hssbem::find_option(name);
  PetscCheck(*row, PETSC_COMM_SELF, PETSC_ERR_PLIB, "option -%s has no row in hssbem's table of options", name);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PETSC_ERR_ARG_OUTOFRANGE with the table's message when v is no value of the row. */
static PetscErrorCode CheckValue_Private(MPI_Comm comm, const hssbem::OptionRow &row, const hssbem::OptionValue &v)
{
  std::string why;

  PetscFunctionBegin;
  PetscCallCXX(why = hssbem::option_value_error(row, v));
  PetscCheck(why.empty(), comm, PETSC_ERR_ARG_OUTOFRANGE, "%s", why.c_str());
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemOptionsGetValue - Reads one option of hssbem's table from the options database, if given,
  and checks it against the table's range.

  Collective

  Level: developer
@*/
PetscErrorCode HssbemOptionsGetValue(MPI_Comm comm, const char *prefix, const hssbem::OptionRow &row, hssbem::OptionValue *value, PetscBool *set)
{
  std::string       key;
  hssbem::OptionValue v = hssbem::OptionValue::default_of(row);

  PetscFunctionBegin;
  PetscCallCXX(key = "-" + std::string(row.name));
  switch (row.kind) {
  case hssbem::OptionKind::Real: {
    PetscReal r = (PetscReal)v.number;
    PetscCall(PetscOptionsGetReal(NULL, prefix, key.c_str(), &r, set));
    v.number = (double)r;
  } break;
  case hssbem::OptionKind::Int: {
    PetscInt i = (PetscInt)v.number;
    PetscCall(PetscOptionsGetInt(NULL, prefix, key.c_str(), &i, set));
    v.number = (double)i;
  } break;
  case hssbem::OptionKind::Bool: {
    PetscBool b = v.number != 0 ? PETSC_TRUE : PETSC_FALSE;
    PetscCall(PetscOptionsGetBool(NULL, prefix, key.c_str(), &b, set));
    v.number = b == PETSC_TRUE ? 1 : 0;
  } break;
  case hssbem::OptionKind::Text:
  case hssbem::OptionKind::Choice: {
    char buf[PETSC_MAX_PATH_LEN] = "";
    PetscCall(PetscOptionsGetString(NULL, prefix, key.c_str(), buf, sizeof(buf), set));
    PetscCallCXX(v.text = buf);
  } break;
  }
  if (!*set) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(CheckValue_Private(comm, row, v));
  PetscCallCXX(*value = v);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemOptionsGetValues - Reads every option of hssbem's table that `reader` reads and that
  applies to one of `jobs`, where the options database gives it.

  Collective

  Level: developer
@*/
PetscErrorCode HssbemOptionsGetValues(MPI_Comm comm, const char *prefix, hssbem::OptionReader reader, unsigned jobs, hssbem::OptionValues *values)
{
  const hssbem::OptionRow *rows = hssbem::option_rows();

  PetscFunctionBegin;
  for (int i = 0; i < hssbem::num_option_rows(); ++i) {
    hssbem::OptionValue v;
    PetscBool           set = PETSC_FALSE;
    if (rows[i].reader != reader || !(rows[i].jobs & jobs)) continue;
    PetscCall(HssbemOptionsGetValue(comm, prefix, rows[i], &v, &set));
    if (set) PetscCallCXX((*values)[std::string(rows[i].name)] = v);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The key and the help line (with the range) of a row, for PETSc's PetscOptions* items. */
static PetscErrorCode ItemText_Private(const char *name, const hssbem::OptionRow **row, std::string *key, std::string *help)
{
  PetscFunctionBegin;
  PetscCall(HssbemOptionRow(name, row));
  PetscCallCXX(*key = "-" + std::string((*row)->name));
  PetscCallCXX(*help = std::string((*row)->help) + " [" + hssbem::option_range_text(**row) + "]");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PetscOptionsReal/Int/Bool (`item`) for the row `name`, then the row's range check (none for a
   Bool). */
template <class T, class Item>
static PetscErrorCode Item_Private(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, T *value, Item &&item)
{
  const hssbem::OptionRow *row;
  std::string              key, help;

  PetscFunctionBegin;
  PetscCall(ItemText_Private(name, &row, &key, &help));
  PetscCall(item(key.c_str(), help.c_str(), manual));
  if (row->kind != hssbem::OptionKind::Bool) PetscCall(CheckValue_Private(PetscOptionsObject->comm, *row, hssbem::OptionValue::of(*row, (double)*value)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemOptionsRealItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscReal *value)
{
  PetscFunctionBegin;
  PetscCall(Item_Private(PetscOptionsObject, name, manual, value, [&](const char *key, const char *help, const char *man) { return PetscOptionsReal(key, help, man, *value, value, NULL); }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemOptionsIntItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscInt *value)
{
  PetscFunctionBegin;
  PetscCall(Item_Private(PetscOptionsObject, name, manual, value, [&](const char *key, const char *help, const char *man) { return PetscOptionsInt(key, help, man, *value, value, NULL); }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode HssbemOptionsBoolItem(PetscOptionItems *PetscOptionsObject, const char *name, const char *manual, PetscBool *value)
{
  PetscFunctionBegin;
  PetscCall(Item_Private(PetscOptionsObject, name, manual, value, [&](const char *key, const char *help, const char *man) { return PetscOptionsBool(key, help, man, *value, value, NULL); }));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemOptionValuePut - Puts the value of option `name` (its row's kind) into values.

  Not Collective

  Level: developer
@*/
PetscErrorCode HssbemOptionValuePut(hssbem::OptionValues *values, const char *name, double value)
{
  const hssbem::OptionRow *row;

  PetscFunctionBegin;
  PetscCall(HssbemOptionRow(name, &row));
  PetscCallCXX((*values)[name] = hssbem::OptionValue::of(*row, value));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/*@C
  HssbemOptionCheck - Checks a value against the range of its option in hssbem's table (for the
  setters of the PETSc objects, so that a setter and its option refuse the same values).

  Collective

  Level: developer
@*/
PetscErrorCode HssbemOptionCheck(MPI_Comm comm, const char *name, double value)
{
  const hssbem::OptionRow *row;

  PetscFunctionBegin;
  PetscCall(HssbemOptionRow(name, &row));
  PetscCall(CheckValue_Private(comm, *row, hssbem::OptionValue::of(*row, value)));
  PetscFunctionReturn(PETSC_SUCCESS);
}
