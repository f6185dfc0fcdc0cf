/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Test-only: an independent evaluation of a GenICam description by aravis's
 * own GenICam engine (libaravis, LGPL; linked into this program only, never
 * into libflatline). test_genicam_files runs it and compares its output with
 * the library's evaluation of the same file against the same registers.
 *
 *   aravis_eval FILE IMAGE
 *
 * FILE is a GenICam XML file (text before the XML declaration is dropped,
 * as aravis's parser would refuse it); IMAGE selects the register contents
 * (register_image.h). The program registers a device whose memory is that
 * image, loads the description with arv_gc_new() and prints one line per
 * fact, tab-separated:
 *
 *   NAME  addr    ok ADDRESS(hex) LENGTH | err MESSAGE   (register nodes)
 *   NAME  int     ok VALUE | err MESSAGE                  (IInteger nodes)
 *   NAME  float   ok VALUE(%.17g) | err MESSAGE           (IFloat nodes)
 *   NAME  enum    ok ENTRY | err MESSAGE                  (Enumeration)
 *   NAME  bool    ok 0|1 | err MESSAGE                    (Boolean)
 *   NAME  string  ok HEXBYTES | err MESSAGE               (IString nodes)
 *   NAME  exec    ok ADDRESS=HEXBYTES;... | err MESSAGE   (Command: the writes)
 *   NAME  imp     ok 0|1 | err MESSAGE                    (pIsImplemented)
 *   NAME  avl     ok 0|1 | err MESSAGE                    (pIsAvailable)
 *   NAME  limit   value|flags NODE                        (see below)
 *
 * aravis 0.8 gives a formula's pVariable a value only when it names an
 * IInteger or IFloat node (arvgcswissknife.c, arvgcconverter.c): a Boolean
 * variable is left out and the formula is evaluated without it (to 0 and no
 * error, as seen on real files). A "limit" line names a feature whose value
 * ("value": through pValue, pAddress, pIndex, pLength, pVariable, ...) or
 * whose pIsImplemented/pIsAvailable ("flags") depends on such a formula;
 * the comparison leaves those facts out and counts them.
 *
 * aravis also drops a formula's evaluation error (division by zero, ABS in
 * an IntSwissKnife, an unknown variable) and goes on with 0
 * (arvgcswissknife.c evaluates with a NULL GError); only its "evaluator"
 * debug category says so, on stderr. This program enables that category
 * at warning level, points stderr at a temporary file and marks a fact
 * evaluated while the file grew: "NAME limit swallowed-value" or
 * "swallowed-flags".
 *
 * aravis also reads a StructEntry's pIsImplemented/pIsAvailable from the
 * entry alone, while the standard makes every element of a StructReg (but
 * its entries) an element of each entry, as if each were a MaskedIntReg:
 * "NAME limit struct" marks an entry whose StructReg has such elements.
 *
 * Messages have tabs and newlines replaced by spaces.
 */
#include <arv.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "register_image.h"

/* ---- a device whose memory is a register image plus what was written ---- */

typedef struct {
    ArvDevice parent;
    unsigned image;
    GHashTable *written;                       /* address -> byte (GUINT_TO_POINTER(byte + 1)) */
    GString *log;                              /* the writes since the last reset */
    GHashTable *limited_value, *limited_flags; /* memo of limited() */
} FltMemDevice;

typedef struct {
    ArvDeviceClass parent_class;
} FltMemDeviceClass;

G_DEFINE_TYPE(FltMemDevice, flt_mem_device, ARV_TYPE_DEVICE)

static gboolean mem_read(ArvDevice *device, guint64 address, guint32 size, void *buffer,
                         GError **error) {
    FltMemDevice *self = (FltMemDevice *)device;
    guint8 *out = buffer;
    (void)error;
    for (guint32 i = 0; i < size; i++) {
        gpointer w = g_hash_table_lookup(self->written, &(guint64){address + i});
        out[i] = w ? (guint8)(GPOINTER_TO_UINT(w) - 1) : flt_image_byte(self->image, address + i);
    }
    return TRUE;
}

static gboolean mem_write(ArvDevice *device, guint64 address, guint32 size, void *buffer,
                          GError **error) {
    FltMemDevice *self = (FltMemDevice *)device;
    const guint8 *in = buffer;
    (void)error;
    g_string_append_printf(self->log, "%s%" G_GINT64_MODIFIER "x=", self->log->len ? ";" : "",
                           address);
    for (guint32 i = 0; i < size; i++) {
        guint64 *key = g_new(guint64, 1);
        *key = address + i;
        g_hash_table_replace(self->written, key, GUINT_TO_POINTER((guint)in[i] + 1));
        g_string_append_printf(self->log, "%02x", in[i]);
    }
    return TRUE;
}

static gboolean mem_read_register(ArvDevice *device, guint64 address, guint32 *value,
                                  GError **error) {
    return mem_read(device, address, 4, value, error);
}

static gboolean mem_write_register(ArvDevice *device, guint64 address, guint32 value,
                                   GError **error) {
    return mem_write(device, address, 4, &value, error);
}

static void flt_mem_device_init(FltMemDevice *self) {
    self->written = g_hash_table_new_full(g_int64_hash, g_int64_equal, g_free, NULL);
    self->log = g_string_new("");
    self->limited_value = g_hash_table_new(NULL, NULL);
    self->limited_flags = g_hash_table_new(NULL, NULL);
}

static void flt_mem_device_finalize(GObject *object) {
    FltMemDevice *self = (FltMemDevice *)object;
    g_hash_table_destroy(self->written);
    g_string_free(self->log, TRUE);
    g_hash_table_destroy(self->limited_value);
    g_hash_table_destroy(self->limited_flags);
    G_OBJECT_CLASS(flt_mem_device_parent_class)->finalize(object);
}

static void flt_mem_device_class_init(FltMemDeviceClass *klass) {
    ArvDeviceClass *device_class = ARV_DEVICE_CLASS(klass);
    G_OBJECT_CLASS(klass)->finalize = flt_mem_device_finalize;
    device_class->read_memory = mem_read;
    device_class->write_memory = mem_write;
    device_class->read_register = mem_read_register;
    device_class->write_register = mem_write_register;
}

static int limited(ArvDomNode *node, gboolean flags, GHashTable *seen);

/* The size of what aravis has written to stderr (a temporary file). */
static long warnings_size(void) {
    fflush(stderr);
    return lseek(2, 0, SEEK_END);
}

/* ---- output ----------------------------------------------------------------- */

static void print_error(const char *name, const char *what, GError *error) {
    printf("%s\t%s\terr\t", name, what);
    for (const char *p = error && error->message ? error->message : "?"; *p; p++)
        putchar(*p == '\t' || *p == '\n' || *p == '\r' ? ' ' : *p);
    putchar('\n');
}

static void print_hex(const char *name, const char *what, const char *bytes, size_t n) {
    printf("%s\t%s\tok\t", name, what);
    for (size_t i = 0; i < n; i++)
        printf("%02x", (unsigned char)bytes[i]);
    putchar('\n');
}

static void evaluate(FltMemDevice *device, ArvGcFeatureNode *node) {
    const char *name = arv_gc_feature_node_get_name(node);
    GError *error = NULL;
    if (name == NULL || ARV_IS_GC_ENUM_ENTRY(node) || ARV_IS_GC_CATEGORY(node) ||
        ARV_IS_GC_PORT(node))
        return;
    if (limited(ARV_DOM_NODE(node), FALSE, device->limited_value))
        printf("%s\tlimit\tvalue\n", name);
    if (limited(ARV_DOM_NODE(node), TRUE, device->limited_flags))
        printf("%s\tlimit\tflags\n", name);
    if (ARV_IS_GC_STRUCT_ENTRY_NODE(node)) {
        ArvDomNode *reg = arv_dom_node_get_parent_node(ARV_DOM_NODE(node));
        for (ArvDomNode *p = arv_dom_node_get_first_child(reg); p;
             p = arv_dom_node_get_next_sibling(p))
            if (ARV_IS_GC_PROPERTY_NODE(p)) {
                ArvGcPropertyNodeType type =
                    arv_gc_property_node_get_node_type(ARV_GC_PROPERTY_NODE(p));
                if (type == ARV_GC_PROPERTY_NODE_TYPE_P_IS_IMPLEMENTED ||
                    type == ARV_GC_PROPERTY_NODE_TYPE_P_IS_AVAILABLE) {
                    printf("%s\tlimit\tstruct\n", name);
                    break;
                }
            }
    }

    long warned = warnings_size();
    if (ARV_IS_GC_REGISTER(node)) {
        guint64 address = arv_gc_register_get_address(ARV_GC_REGISTER(node), &error);
        guint64 length = 0;
        if (error == NULL)
            length = arv_gc_register_get_length(ARV_GC_REGISTER(node), &error);
        if (error)
            print_error(name, "addr", error);
        else
            printf("%s\taddr\tok\t%" G_GINT64_MODIFIER "x\t%" G_GUINT64_FORMAT "\n", name, address,
                   length);
        g_clear_error(&error);
    }
    if (ARV_IS_GC_ENUMERATION(node)) {
        gint64 v = arv_gc_enumeration_get_int_value(ARV_GC_ENUMERATION(node), &error);
        if (error)
            print_error(name, "int", error);
        else
            printf("%s\tint\tok\t%" G_GINT64_FORMAT "\n", name, v);
        g_clear_error(&error);
        const char *entry = arv_gc_enumeration_get_string_value(ARV_GC_ENUMERATION(node), &error);
        if (error)
            print_error(name, "enum", error);
        else
            printf("%s\tenum\tok\t%s\n", name, entry ? entry : "");
        g_clear_error(&error);
    } else if (ARV_IS_GC_INTEGER(node)) {
        gint64 v = arv_gc_integer_get_value(ARV_GC_INTEGER(node), &error);
        if (error)
            print_error(name, "int", error);
        else
            printf("%s\tint\tok\t%" G_GINT64_FORMAT "\n", name, v);
        g_clear_error(&error);
    } else if (ARV_IS_GC_FLOAT(node)) {
        double v = arv_gc_float_get_value(ARV_GC_FLOAT(node), &error);
        if (error)
            print_error(name, "float", error);
        else
            printf("%s\tfloat\tok\t%.17g\n", name, v);
        g_clear_error(&error);
    } else if (ARV_IS_GC_BOOLEAN(node)) {
        gboolean v = arv_gc_boolean_get_value(ARV_GC_BOOLEAN(node), &error);
        if (error)
            print_error(name, "bool", error);
        else
            printf("%s\tbool\tok\t%d\n", name, v ? 1 : 0);
        g_clear_error(&error);
    } else if (ARV_IS_GC_STRING(node)) {
        const char *v = arv_gc_string_get_value(ARV_GC_STRING(node), &error);
        if (error)
            print_error(name, "string", error);
        else
            print_hex(name, "string", v ? v : "", v ? strlen(v) : 0);
        g_clear_error(&error);
    } else if (ARV_IS_GC_COMMAND(node)) {
        g_string_truncate(device->log, 0);
        arv_gc_command_execute(ARV_GC_COMMAND(node), &error);
        if (error)
            print_error(name, "exec", error);
        else
            printf("%s\texec\tok\t%s\n", name, device->log->str);
        g_clear_error(&error);
        g_hash_table_remove_all(device->written); /* back to the image */
    }

    if (warnings_size() != warned)
        printf("%s\tlimit\tswallowed-value\n", name);
    warned = warnings_size();
    gboolean implemented = arv_gc_feature_node_is_implemented(node, &error);
    if (error)
        print_error(name, "imp", error);
    else
        printf("%s\timp\tok\t%d\n", name, implemented ? 1 : 0);
    g_clear_error(&error);
    gboolean available = arv_gc_feature_node_is_available(node, &error);
    if (error)
        print_error(name, "avl", error);
    else
        printf("%s\tavl\tok\t%d\n", name, available ? 1 : 0);
    g_clear_error(&error);
    if (warnings_size() != warned)
        printf("%s\tlimit\tswallowed-flags\n", name);
}

/* ---- where aravis's evaluation is known to be incomplete ------------------- */

static gboolean is_formula_node(ArvDomNode *node) {
    return ARV_IS_GC_SWISS_KNIFE(node) || ARV_IS_GC_CONVERTER(node);
}

/* 1: the node (or what it reads) has a formula with a variable aravis leaves
 * out; 0: not; memo in `seen` (2 = being visited: a loop, taken as 0). */
static int limited(ArvDomNode *node, gboolean flags, GHashTable *seen) {
    gpointer memo = g_hash_table_lookup(seen, node);
    if (memo)
        return GPOINTER_TO_INT(memo) == 1;
    g_hash_table_insert(seen, node, GINT_TO_POINTER(2));
    int result = 0;
    for (ArvDomNode *child = arv_dom_node_get_first_child(node); child && !result;
         child = arv_dom_node_get_next_sibling(child)) {
        if (ARV_IS_GC_PROPERTY_NODE(child)) {
            ArvGcPropertyNodeType type =
                arv_gc_property_node_get_node_type(ARV_GC_PROPERTY_NODE(child));
            if (type < ARV_GC_PROPERTY_NODE_TYPE_P_UNKNONW ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_FEATURE ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_SELECTED ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_INVALIDATOR ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_PORT ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_MINIMUM ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_MAXIMUM ||
                type == ARV_GC_PROPERTY_NODE_TYPE_P_INCREMENT)
                continue;
            if (!flags && (type == ARV_GC_PROPERTY_NODE_TYPE_P_IS_IMPLEMENTED ||
                           type == ARV_GC_PROPERTY_NODE_TYPE_P_IS_AVAILABLE ||
                           type == ARV_GC_PROPERTY_NODE_TYPE_P_IS_LOCKED))
                continue;
            ArvGcNode *linked = arv_gc_property_node_get_linked_node(ARV_GC_PROPERTY_NODE(child));
            if (linked == NULL)
                continue;
            if (type == ARV_GC_PROPERTY_NODE_TYPE_P_VARIABLE && is_formula_node(node) &&
                !ARV_IS_GC_INTEGER(linked) && !ARV_IS_GC_FLOAT(linked))
                result = 1;
            else
                result = limited(ARV_DOM_NODE(linked), flags, seen);
        } else if (ARV_IS_GC_FEATURE_NODE(child) && !ARV_IS_GC_ENUM_ENTRY(child)) {
            /* an IntSwissKnife inside a register: a term of its address */
            result = limited(child, flags, seen);
        } else if (ARV_IS_GC_ENUM_ENTRY(child) && flags) {
            result = limited(child, flags, seen);
        }
    }
    g_hash_table_insert(seen, node, GINT_TO_POINTER(result ? 1 : 3));
    return result;
}

/* Every feature node: the document element's children, into Groups and
 * StructRegs (whose StructEntries are the features). */
static void walk(FltMemDevice *device, ArvDomNode *parent) {
    for (ArvDomNode *child = arv_dom_node_get_first_child(parent); child != NULL;
         child = arv_dom_node_get_next_sibling(child)) {
        if (ARV_IS_GC_GROUP_NODE(child) || ARV_IS_GC_STRUCT_REG_NODE(child))
            walk(device, child);
        if (ARV_IS_GC_FEATURE_NODE(child))
            evaluate(device, ARV_GC_FEATURE_NODE(child));
    }
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s FILE IMAGE\n", argv[0]);
        return 2;
    }
    gchar *xml = NULL;
    gsize size = 0;
    if (!g_file_get_contents(argv[1], &xml, &size, NULL)) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 2;
    }
    /* Text before the declaration (a dump's header line, a byte-order mark). */
    const char *start = g_strstr_len(xml, (gssize)size, "<?xml");
    if (start == NULL) {
        start = xml;
        if (size >= 3 && (unsigned char)xml[0] == 0xEF && (unsigned char)xml[1] == 0xBB &&
            (unsigned char)xml[2] == 0xBF)
            start += 3;
    }
    /* aravis's evaluator warnings go to a temporary file (see above). */
    FILE *warnings = tmpfile();
    if (warnings == NULL || dup2(fileno(warnings), 2) < 0 || !arv_debug_enable("evaluator:1")) {
        fprintf(stdout, "cannot capture aravis's evaluator warnings\n");
        return 2;
    }
    FltMemDevice *device = g_object_new(flt_mem_device_get_type(), NULL);
    device->image = (unsigned)atoi(argv[2]);
    ArvGc *gc = arv_gc_new(ARV_DEVICE(device), start, size - (gsize)(start - xml));
    if (gc == NULL) {
        fprintf(stderr, "aravis does not load %s\n", argv[1]);
        return 1;
    }
    arv_gc_set_register_cache_policy(gc, ARV_REGISTER_CACHE_POLICY_DISABLE);
    arv_gc_set_range_check_policy(gc, ARV_RANGE_CHECK_POLICY_DISABLE);
    walk(device, ARV_DOM_NODE(arv_dom_document_get_document_element(ARV_DOM_DOCUMENT(gc))));
    g_object_unref(gc);
    g_object_unref(device);
    g_free(xml);
    return 0;
}
