// contact: placeholder translation unit until the contact module lands (keeps the library target non-empty).
namespace fdem::contact {
int module_version() { return 0; }
}  // namespace fdem::contact
